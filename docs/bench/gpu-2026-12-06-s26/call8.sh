#!/usr/bin/env bash
# Twenty-sixth session, call 8: the wide top level again, its hit leaf instances visited nearest first as the
# node's slots tell (descending slot ^ ray octant, the order of its inner children) instead of in instance order.
# rel/head0.xz = 64ba9fc (the BVH2 top level); relb/head.xz = 1b70758 + wide-tlas.patch + the ordering. The crowd
# and the seed-like interior at 2560x1440, 1 spp, both forms, alternating -> ordered.txt. Carry [".gl", "relb", "rel"].
set -u
source scripts/gpu-unpack.sh head0
rows() {
  local w; w=$(mktemp -d); local label=$1 bin=$2 scene=$3; shift 3
  $bin bench --suite full --parts frames --scene "$scene" "$@" \
    --frames 24 --assets relb/assets --out "$w" --cache "$w/c" > "$w/log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']:
    b=row.get('traversal_per_bounce_ray') or {}
    print('$label', row['scene'], round(row['trace_ms_median'],3), round(row['frame_ms']['median'],3), row['integrator'], round(b.get('tlas_nodes',0),3), round(b.get('bvh2_nodes',0),3), round(b.get('wide_nodes',0),3))
" >> "$OUT/ordered.txt" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
for round in 1 2; do
  for scene in crowd seed-interior; do
    for form in megakernel wavefront; do
      rows bvh2-$form rel/head0 $scene --width 2560 --height 1440 --integrator $form
      rows wide-ordered-$form relb/head $scene --width 2560 --height 1440 --integrator $form
    done
  done
  echo "round $round: $(elapsed) s" >> "$OUT/ordered.txt"
  [ "$(elapsed)" -gt 100 ] && break
done
cat "$OUT/gpu.txt" "$OUT/ordered.txt"; cat "$OUT/errors.txt" 2>/dev/null
