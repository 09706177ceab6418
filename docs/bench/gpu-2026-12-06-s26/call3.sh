#!/usr/bin/env bash
# Twenty-sixth session, call 3: deformable meshes' trees with the slowest preset where the GPU deforms them.
# rel/base.xz = b89df3c (+ call 2's probe, inert without its variables); relb/head.xz = the working tree with
# `gpu_deformed_bvh_quality` (VerySlow at upload and at every rebuild on the GPU backend). The seed-like interior
# and the crowd, 2560x1440, 1 spp, depth 6, 24 frames, the binaries alternating, three rounds -> deform.txt
# (label, scene, trace ms median, frame ms median, rebuilds, form, traversal per bounce ray: TLAS, BVH2 nodes,
# triangles). Carry [".gl", "relb", "rel"].
set -u
source scripts/gpu-unpack.sh base
rows() {
  local w; w=$(mktemp -d); local label=$1 bin=$2 scene=$3
  $bin bench --suite full --parts frames --scene "$scene" --width 2560 --height 1440 \
    --frames 24 --integrator auto --assets relb/assets --out "$w" --cache "$w/c" > "$w/log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']:
    b=row.get('traversal_per_bounce_ray') or {}
    print('$label', row['scene'], round(row['trace_ms_median'],3), round(row['frame_ms']['median'],3), row.get('bvh_rebuilds'), row['integrator'], round(b.get('tlas_nodes',0),3), round(b.get('bvh2_nodes',0),3), round(b.get('triangles',0),3))
" >> "$OUT/deform.txt" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
for round in 1 2 3; do
  for scene in seed-interior crowd; do
    rows base rel/base $scene
    rows head relb/head $scene
  done
  echo "round $round: $(elapsed) s" >> "$OUT/deform.txt"
  [ "$(elapsed)" -gt 200 ] && break
done
cat "$OUT/gpu.txt" "$OUT/deform.txt"; cat "$OUT/errors.txt" 2>/dev/null
