#!/usr/bin/env bash
# Twenty-sixth session, call 2: the presets of the trees built while a scene plays (a probe, not committed:
# RAYKIN_PROBE_TLAS names the top level's obvhs preset, fast_build before; RAYKIN_PROBE_DEFORM the deformable
# meshes' BVH2 preset at load and at every rebuild, Medium before). relb/head.xz = b89df3c + the probe.
# The seed-like interior and the crowd (the probe's call 2a ran the crowd only), 2560x1440, 1 spp, depth 6, 24 frames, the variants alternating, two
# rounds -> presets.txt (label, scene, trace ms median, frame ms median, rebuilds, traversal per bounce ray).
set -u
source scripts/gpu-unpack.sh
rows() {
  local w; w=$(mktemp -d); local label=$1 scene=$2; shift 2
  env "$@" relb/head bench --suite full --parts frames --scene "$scene" --width 2560 --height 1440 \
    --frames 24 --integrator auto --assets relb/assets --out "$w" --cache "$w/c" > "$w/log" 2>&1
  python3 -c "
import json, statistics; r=json.load(open('$w/results.json'))
for row in r['rows']:
    b=row.get('traversal_per_bounce_ray') or {}
    print('$label', row['scene'], round(row['trace_ms_median'],3), round(row['frame_ms']['median'],3), row.get('bvh_rebuilds'), row['integrator'], round(b.get('tlas_nodes',0),3), round(b.get('bvh2_nodes',0),3), round(b.get('triangles',0),3))
" >> "$OUT/presets.txt" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
for round in 1 2; do
  for scene in seed-interior crowd; do
    rows base $scene RAYKIN_UNUSED=1
    rows tlas-medium $scene RAYKIN_PROBE_TLAS=medium
    rows tlas-veryslow $scene RAYKIN_PROBE_TLAS=veryslow
    rows deform-veryslow $scene RAYKIN_PROBE_DEFORM=veryslow
    rows medium-veryslow $scene RAYKIN_PROBE_TLAS=medium RAYKIN_PROBE_DEFORM=veryslow
    rows both-veryslow $scene RAYKIN_PROBE_TLAS=veryslow RAYKIN_PROBE_DEFORM=veryslow
  done
  echo "round $round: $(elapsed) s" >> "$OUT/presets.txt"
  [ "$(elapsed)" -gt 250 ] && break
done
cat "$OUT/gpu.txt" "$OUT/presets.txt"; cat "$OUT/errors.txt" 2>/dev/null
