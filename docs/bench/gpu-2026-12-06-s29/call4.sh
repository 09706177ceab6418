#!/usr/bin/env bash
# Twenty-ninth session, call 4: the session's head (relb/commit) under `--integrator auto`, the deforming meshes'
# wide trees on and off (RAYKIN_WIDE_DEFORMED), on the seed-like interior and the crowd (2560x1440, 1 spp, depth
# 6, 24 frames), two rounds; and an experiment (the binary is the head plus leaf3.patch, RAYKIN_WIDE_LEAF3=on:
# the deforming meshes' BVH2s built with leaves of at most 3 triangles, one wide slot each, instead of 4) under
# auto and with each form forced on the seed -> head.txt (the columns of call2.sh's wide.txt). Carry [".gl", "relb"].
set -u
source scripts/gpu-unpack.sh
rows() {
  local w; w=$(mktemp -d); local label=$1 envs=$2 scene=$3; shift 3
  [ "$(elapsed)" -lt 360 ] || return
  env $envs timeout 80 relb/head bench --suite full --parts frames --scene "$scene" "$@" \
    --frames 24 --assets relb/assets --out "$w" --cache "$w/c" > "$w/log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']:
    b=row['traversal_per_bounce_ray']
    print('$label', row['scene'], row['width'], round(row['trace_ms_median'],3), round(row['frame_ms']['median'],3), row['integrator'], row.get('rays_sorted'), round(row['skin_refit_ms_per_100k_tris'],4), round(row['gpu_memory_geometry_bvh_mib'],1), *[round(b[k],2) for k in ('tlas_nodes','bvh2_nodes','wide_nodes','triangles','bytes')])
" >> "$OUT/head.txt" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
for round in 1 2; do
  for scene in seed-interior crowd; do
    rows auto-wide "RAYKIN_WIDE_DEFORMED=on" $scene --width 2560 --height 1440 --integrator auto
    rows auto-bvh2 "RAYKIN_WIDE_DEFORMED=off" $scene --width 2560 --height 1440 --integrator auto
    rows auto-leaf3 "RAYKIN_WIDE_LEAF3=on" $scene --width 2560 --height 1440 --integrator auto
  done
done
# The seed's waves and megakernel forced, leaves of 4 against 3 triangles.
for round in 1 2; do
  for f in wavefront megakernel; do
    rows $f-leaf4 "RAYKIN_WAVE_SORT=on" seed-interior --width 2560 --height 1440 --integrator $f
    rows $f-leaf3 "RAYKIN_WAVE_SORT=on RAYKIN_WIDE_LEAF3=on" seed-interior --width 2560 --height 1440 --integrator $f
  done
done
echo "head: $(elapsed) s" >> "$OUT/head.txt"
cat "$OUT/gpu.txt" "$OUT/head.txt"; cat "$OUT/errors.txt" 2>/dev/null; true
