#!/usr/bin/env bash
# Device call: which change moved the trace time: the new binary with 2bed230's tlas.wgsl or bvh2.wgsl put back
# through RAYKIN_SHADER_DIR (rel/sd_*), beside both binaries as they are; two rounds.
set -u
for f in .gl/*.deb; do dpkg -x $f / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
(cd rel && xz -dkf raykin-old.xz && xz -dkf raykin-new.xz && chmod +x raykin-old raykin-new)
for round in 1 2; do
  for v in old new new-tlasold new-bvhold; do
    b=raykin-${v%%-*}; dir=/nonexistent
    case $v in *-*) dir=rel/sd_${v#*-} ;; esac
    w=$(mktemp -d)
    RAYKIN_SHADER_DIR=$dir rel/$b bench --suite full --parts frames --frames 40 --scene cornell --scene flight-helmet --scene spheres --scene crowd \
      --assets shared/assets --out "$w" --cache "$w/c" >> "$OUT/bench.log" 2>&1
    python3 -c "
import json,sys; r=json.load(open('$w/results.json'))
for row in r['rows']: print('$v', $round, row.get('scene'), row.get('width'), row.get('height'), row.get('trace_ms_median', row.get('trace_ms')))
" >> "$OUT/ab.txt"
  done
done
awk '{k=$3" "$4" "$1; s[k]+=$6; n[k]++} END {for (k in s) print k, s[k]/n[k]}' "$OUT/ab.txt" | sort
