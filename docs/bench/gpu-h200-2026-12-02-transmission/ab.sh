#!/usr/bin/env bash
# Device call: trace time before (a1d0057) and after (extension lobes with kernels specialised per scene:
# MATERIAL_LOBES pipeline constant), alternating twice; then AttenuationTest (Factors kernel) rendered by both.
set -u
for f in .gl/*.deb; do dpkg -x $f / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
(cd rel && xz -dkf raykin-old.xz && xz -dkf raykin-spec.xz && chmod +x raykin-old raykin-spec)
for round in 1 2; do
  for b in raykin-old raykin-spec; do
    w=$(mktemp -d)
    rel/$b bench --suite full --parts frames --frames 40 --scene cornell --scene flight-helmet --scene spheres --scene crowd \
      --assets shared/assets --out "$w" --cache "$w/c" >> "$OUT/bench.log" 2>&1
    python3 -c "
import json,sys; r=json.load(open('$w/results.json'))
for row in r['rows']: print('$b', $round, row.get('scene'), row.get('width'), row.get('height'), row.get('trace_ms_median', row.get('trace_ms')))
" >> "$OUT/ab.txt"
  done
done
awk '{k=$3" "$4" "$1; s[k]+=$6; n[k]++} END {for (k in s) print k, s[k]/n[k]}' "$OUT/ab.txt" | sort
for b in raykin-old raykin-spec; do
  rel/$b render shared/assets/AttenuationTest/glTF/AttenuationTest.gltf --spp 1024 --width 1280 --height 720 --max-depth 12 \
    --look-from 0.5,0,17 --look-at 0.5,0,0 --fov 45 --out "$OUT/attenuation-$b.png" >> "$OUT/render.log" 2>&1
done
grep wrote "$OUT/render.log"
