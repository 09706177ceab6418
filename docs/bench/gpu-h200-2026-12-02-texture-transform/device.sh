#!/usr/bin/env bash
# Device call: trace time before (711cae3) and after (bd4e9d4: texture-info entries of 48 B with UV rows), alternating twice.
set -u
for f in .gl/*.deb; do dpkg -x $f / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
(cd rel && xz -dkf raykin.xz && xz -dkf raykin-tt.xz && chmod +x raykin raykin-tt)
for round in 1 2; do
  for b in raykin raykin-tt; do
    w=$(mktemp -d)
    rel/$b bench --suite full --parts frames --frames 40 --scene cornell --scene flight-helmet --scene spheres --scene crowd \
      --assets shared/assets --out "$w" --cache "$w/c" >> "$OUT/bench.log" 2>&1
    python3 -c "
import json,sys; r=json.load(open('$w/results.json'))
for row in r['rows']: print('$b', $round, row.get('scene'), row.get('width'), row.get('height'), row.get('trace_ms_median', row.get('trace_ms')))
" | tee -a "$OUT/ab.txt"

  done
done
