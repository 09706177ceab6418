#!/usr/bin/env bash
# Twenty-eighth session, call 3 (call 2, the sort keys alone, never got a machine; its variants are part 2 here).
# relb/head.xz = 8990964 (built from its code before the commit): the waves traverse a
#   compressed 8-wide top-level tree built beside the BVH2 (RAYKIN_WIDE_TOP_LEVEL=off keeps the BVH2); the
#   megakernel keeps the BVH2, now read from the top level's buffer as 16-byte words.
# rel/paths.xz = c08b4cf (the BVH2 read as whole nodes).
# 1. The seed-like interior and the crowd at 2560x1440, 1 spp, depth 6: the waves forced and sorted with the wide
#    top level, without it, and c08b4cf; the megakernel forced (head against c08b4cf: the word reads); auto (head)
#    -> wide.txt (label, scene, width, trace ms median, frame ms median, form, rays sorted, forms trial, sort trial).
# (Rows stop starting after 150 s: the session had little device time left.)
# 2. The sort's key: c08b4cf with variants of `sort_key` through RAYKIN_SHADER_DIR (keys/NAME/wavefront.wgsl, made
#    by ../sort-key-variants.patch from c08b4cf's engine/src/render/passes/wavefront/wavefront.wgsl; same
#    images bit for bit on lavapipe): oBdD = B origin bits an axis and an octahedral direction cell of D bits an
#    axis, oBoct = B bits and the octant (o4oct is the committed key) -> keys.txt.
# Carry [".gl", "relb", "rel"].
set -u
source scripts/gpu-unpack.sh paths
rows() {
  local w; w=$(mktemp -d); local file=$1 label=$2 bin=$3 dir=$4 envs=$5 scene=$6; shift 6
  [ "$(elapsed)" -lt 150 ] || return
  env RAYKIN_SHADER_DIR=$dir $envs timeout 60 $bin bench --suite full --parts frames --scene "$scene" "$@" \
    --frames 24 --assets relb/assets --out "$w" --cache "$w/c" > "$w/log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']:
    print('$label', row['scene'], row['width'], round(row['trace_ms_median'],3), round(row['frame_ms']['median'],3), row['integrator'], row.get('rays_sorted'), str(row.get('auto_trial_ms')).replace(' ',''), str(row.get('sort_trial_ms')).replace(' ',''))
" >> "$OUT/$file" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
big="--width 2560 --height 1440"
for round in 1 2; do
  for scene in seed-interior crowd; do
    rows wide.txt waves-wide relb/head /none "RAYKIN_WAVE_SORT=on RAYKIN_WIDE_TOP_LEVEL=on" $scene $big --integrator wavefront
    rows wide.txt waves-bvh2 relb/head /none "RAYKIN_WAVE_SORT=on RAYKIN_WIDE_TOP_LEVEL=off" $scene $big --integrator wavefront
    rows wide.txt waves-c08b4cf rel/paths /none "RAYKIN_WAVE_SORT=on" $scene $big --integrator wavefront
    rows wide.txt mega-head relb/head /none "RAYKIN_X=1" $scene $big --integrator megakernel
    rows wide.txt mega-c08b4cf rel/paths /none "RAYKIN_X=1" $scene $big --integrator megakernel
  done
done
for scene in seed-interior crowd; do rows wide.txt auto relb/head /none "RAYKIN_X=1" $scene $big --integrator auto; done
echo "wide: $(elapsed) s" >> "$OUT/wide.txt"
for round in 1 2; do
  for scene in seed-interior crowd; do
    for v in o4oct o5 o3d3 o2d4 o1d6; do
      rows keys.txt $v rel/paths keys/$v "RAYKIN_WAVE_SORT=on" $scene $big --integrator wavefront
    done
  done
done
echo "keys: $(elapsed) s" >> "$OUT/keys.txt"
cat "$OUT/gpu.txt" "$OUT/wide.txt" "$OUT/keys.txt"; cat "$OUT/errors.txt" 2>/dev/null; true
