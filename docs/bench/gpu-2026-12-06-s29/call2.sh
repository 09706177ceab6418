#!/usr/bin/env bash
# Twenty-ninth session, call 2. relb/head.xz = the deforming meshes' wide trees (collapsed from their BVH2s,
# re-quantised after every refit; RAYKIN_WIDE_DEFORMED=off keeps the BVH2s for every kernel).
# The seed-like interior and the crowd at 2560x1440, 1 spp, depth 6, three rounds: the waves (sorted) and the
# megakernel forced, each with the wide trees on and off; then auto on and off (also the interior) -> wide.txt:
# label, scene, width, trace ms median, frame ms median, form, rays sorted, skin+refit ms per 100k deforming
# triangles, geometry+BVH MiB, per bounce ray: top-level nodes, BVH2 nodes, wide nodes, triangles, bytes.
# Carry [".gl", "relb"].
set -u
source scripts/gpu-unpack.sh
rows() {
  local w; w=$(mktemp -d); local label=$1 envs=$2 scene=$3; shift 3
  [ "$(elapsed)" -lt 500 ] || return
  env $envs timeout 80 relb/head bench --suite full --parts frames --scene "$scene" "$@" \
    --frames 24 --assets relb/assets --out "$w" --cache "$w/c" > "$w/log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']:
    b=row['traversal_per_bounce_ray']
    print('$label', row['scene'], row['width'], round(row['trace_ms_median'],3), round(row['frame_ms']['median'],3), row['integrator'], row.get('rays_sorted'), round(row['skin_refit_ms_per_100k_tris'],4), round(row['gpu_memory_geometry_bvh_mib'],1), *[round(b[k],2) for k in ('tlas_nodes','bvh2_nodes','wide_nodes','triangles','bytes')])
" >> "$OUT/wide.txt" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
big="--width 2560 --height 1440"
for round in 1 2 3; do
  for scene in seed-interior crowd; do
    rows waves-wide "RAYKIN_WAVE_SORT=on RAYKIN_WIDE_DEFORMED=on" $scene $big --integrator wavefront
    rows waves-bvh2 "RAYKIN_WAVE_SORT=on RAYKIN_WIDE_DEFORMED=off" $scene $big --integrator wavefront
    rows mega-wide "RAYKIN_WIDE_DEFORMED=on" $scene $big --integrator megakernel
    rows mega-bvh2 "RAYKIN_WIDE_DEFORMED=off" $scene $big --integrator megakernel
  done
done
for scene in seed-interior crowd interior; do
  rows auto-wide "RAYKIN_WIDE_DEFORMED=on" $scene $big --integrator auto
  rows auto-bvh2 "RAYKIN_WIDE_DEFORMED=off" $scene $big --integrator auto
done
echo "wide: $(elapsed) s" >> "$OUT/wide.txt"
cat "$OUT/gpu.txt" "$OUT/wide.txt"; cat "$OUT/errors.txt" 2>/dev/null; true
