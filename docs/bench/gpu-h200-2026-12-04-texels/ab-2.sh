#!/usr/bin/env bash
# Device call, second round: the environment's column wrap by selects instead of an integer remainder
# (rel/raykin-u.xz) against ca2d40e (rel/raykin-t.xz), and the CPU adapters' read-only storage-texture form
# forced on the GPU (RAYKIN_SCENE_READS=textures), alternating ROUNDS times: the bench's frame loop, trace kernel
# median of 60 frames per size. Carry .gl and rel (rel/assets: CornellBox, FlightHelmet,
# MetalRoughSpheresNoTextures, CesiumMan, Fox).
set -u
rounds=${1:-2}
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
(cd rel && xz -dkf raykin-t.xz && xz -dkf raykin-u.xz && chmod +x raykin-t raykin-u)
scenes=(--scene cornell --scene flight-helmet --scene spheres --scene env-lit --scene crowd)
one() { # label binary reads round
  local v=$1 bin=$2 reads=$3 round=$4
  local w; w=$(mktemp -d)
  RAYKIN_SCENE_READS=$reads "rel/$bin" bench --suite full --parts frames --frames 60 "${scenes[@]}" --assets rel/assets \
    --out "$w" --cache "$w/c" >> "$OUT/bench.log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']: print('$v', $round, row.get('scene'), row.get('width'), row.get('height'), row.get('trace_ms_median'))
" >> "$OUT/ab.txt"
}
for round in $(seq "$rounds"); do
  one before raykin-t buffers "$round"; one after raykin-u buffers "$round"; one storage-texels raykin-u textures "$round"
done
awk '{k=$3" "$4"x"$5" "$1; s[k]+=$6; n[k]++} END {for (k in s) printf "%s trace_ms %.4f (n=%d)\n", k, s[k]/n[k], n[k]}' \
  "$OUT/ab.txt" | sort | tee "$OUT/summary.txt"
