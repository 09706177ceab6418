#!/usr/bin/env bash
# Twenty-seventh session, call 1: each bounce's rays sorted before extend traces them (`RAYKIN_WAVE_SORT=on`,
# the counting sort by origin cell and direction octant in wavefront.wgsl) against the same binary unsorted.
# The waves fixed: the seed-like interior and the crowd at 2560x1440, 1 spp, depth 6, 24 frames; the static
# scenes at 960x540, 16 spp a frame; two rounds, sort off and on alternating -> sort.txt (label, scene, width,
# trace ms median, frame ms median, form, traversal per bounce ray: TLAS, BVH2, wide nodes, triangles).
# Carry [".gl", "relb"].
set -u
source scripts/gpu-unpack.sh
rows() {
  local w; w=$(mktemp -d); local label=$1 sort=$2 scene=$3; shift 3
  RAYKIN_WAVE_SORT=$sort relb/head bench --suite full --parts frames --scene "$scene" "$@" \
    --frames 24 --assets relb/assets --out "$w" --cache "$w/c" > "$w/log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']:
    b=row.get('traversal_per_bounce_ray') or {}
    print('$label', row['scene'], row['width'], round(row['trace_ms_median'],3), round(row['frame_ms']['median'],3), row['integrator'], round(b.get('tlas_nodes',0),3), round(b.get('bvh2_nodes',0),3), round(b.get('wide_nodes',0),3), round(b.get('triangles',0),3))
" >> "$OUT/sort.txt" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
for round in 1 2; do
  for scene in seed-interior crowd; do
    for sort in off on; do
      rows sort-$sort $sort $scene --width 2560 --height 1440 --integrator wavefront
    done
  done
  for scene in cornell flight-helmet spheres env-lit many-lights; do
    for sort in off on; do
      rows sort-$sort $sort $scene --width 960 --height 540 --spp-per-frame 16 --integrator wavefront
    done
  done
  echo "round $round: $(elapsed) s" >> "$OUT/sort.txt"
  [ "$(elapsed)" -gt 260 ] && break
done
cat "$OUT/gpu.txt" "$OUT/sort.txt"; cat "$OUT/errors.txt" 2>/dev/null
