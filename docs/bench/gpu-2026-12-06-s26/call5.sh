#!/usr/bin/env bash
# Twenty-sixth session, call 5: the top level as a compressed wide tree (call 4 again: its head's auto trial,
# which now waits for half a second of trace time, did not decide within the bench's 0.6 s warm-up, so its timed
# frames alternated the forms; the bench's warm-up now runs until auto decides). rel/deform.xz = 4a1feba (deformable
# meshes' trees VerySlow on the GPU backend: call 3's head); relb/head.xz = the working tree with the wide top
# level. The seed-like interior and the crowd at 2560x1440, 1 spp, depth 6, 24 frames; FlightHelmet
# and the Cornell box (one merged leaf each: the top-level loop compiled away, controls) at 960x540, 16 spp a frame;
# the binaries alternating, two rounds -> tlas.txt (label, scene, trace ms median, frame ms median, rebuilds, form,
# traversal per bounce ray: TLAS nodes, BVH2 nodes, triangles). Carry [".gl", "relb", "rel"].
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
    print('$label', row['scene'], row['width'], str(row.get('auto_trial_ms')).replace(' ',''), round(row['trace_ms_median'],3), round(row['frame_ms']['median'],3), row.get('bvh_rebuilds'), row['integrator'], round(b.get('tlas_nodes',0),3), round(b.get('bvh2_nodes',0),3), round(b.get('triangles',0),3))
" >> "$OUT/tlas.txt" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
for round in 1 2; do
  for scene in seed-interior crowd; do
    for form in auto megakernel wavefront; do
      rows before-$form rel/deform $scene --width 2560 --height 1440 --integrator $form
      rows wide-$form relb/head $scene --width 2560 --height 1440 --integrator $form
    done
  done
  for scene in flight-helmet cornell; do
    rows before rel/deform $scene --width 960 --height 540 --spp-per-frame 16 --integrator auto
    rows wide relb/head $scene --width 960 --height 540 --spp-per-frame 16 --integrator auto
  done
  echo "round $round: $(elapsed) s" >> "$OUT/tlas.txt"
  [ "$(elapsed)" -gt 230 ] && break
done
cat "$OUT/gpu.txt" "$OUT/tlas.txt"; cat "$OUT/errors.txt" 2>/dev/null
