#!/usr/bin/env bash
# Device call: trace time before (2bed230) and after (parameters in storage buffers instead of uniforms, both leaf
# children through one traversal call site), two dev-profile binaries alternating twice; bench scenes, frame loop.
set -u
for f in .gl/*.deb; do dpkg -x $f / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
(cd rel && xz -dkf raykin-old.xz && xz -dkf raykin-new.xz && chmod +x raykin-old raykin-new)
for round in 1 2; do
  for b in raykin-old raykin-new; do
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
