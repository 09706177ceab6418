#!/usr/bin/env bash
# Twenty-sixth session, call 6: a probe of why the wide top level slows the megakernel (call 5: the crowd 1.03x,
# the seed-like interior 1.11x) while it speeds the waves (0.91x, 0.94x). With `--static-bvh binary` every BLAS
# is a BVH2, so the megakernel holds one copy of the wide node test (the top level's) instead of two: if the
# second copy's registers are the cost, the wide top level should gain there. Binaries as in call 5; the crowd
# and the seed-like interior at 2560x1440, 1 spp, both forms, alternating, two rounds -> probe.txt.
set -u
source scripts/gpu-unpack.sh deform
rows() {
  local w; w=$(mktemp -d); local label=$1 bin=$2 scene=$3; shift 3
  $bin bench --suite full --parts frames --scene "$scene" "$@" \
    --frames 24 --assets relb/assets --out "$w" --cache "$w/c" > "$w/log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']:
    b=row.get('traversal_per_bounce_ray') or {}
    print('$label', row['scene'], round(row['trace_ms_median'],3), round(row['frame_ms']['median'],3), row['integrator'], round(b.get('tlas_nodes',0),3), round(b.get('bvh2_nodes',0),3), round(b.get('wide_nodes',0),3))
" >> "$OUT/probe.txt" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
for round in 1 2; do
  for scene in crowd seed-interior; do
    for form in megakernel wavefront; do
      rows before-binary-$form rel/deform $scene --width 2560 --height 1440 --integrator $form --static-bvh binary
      rows wide-binary-$form relb/head $scene --width 2560 --height 1440 --integrator $form --static-bvh binary
    done
  done
  echo "round $round: $(elapsed) s" >> "$OUT/probe.txt"
  [ "$(elapsed)" -gt 150 ] && break
done
cat "$OUT/gpu.txt" "$OUT/probe.txt"; cat "$OUT/errors.txt" 2>/dev/null
