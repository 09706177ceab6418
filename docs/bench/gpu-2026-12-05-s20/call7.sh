#!/usr/bin/env bash
# Twentieth session, call 7, scripted but not run (too little device time was left): call5.sh (the side by side,
# Mitsuba's median of three renders per count) on whichever card the status offers (it offered an H200), the
# side by side cut at 230 s.
set -u
start=$(date +%s)
elapsed() { echo $(( $(date +%s) - start )); }
source scripts/gpu-unpack.sh
(cd relb && xz -dkf head.xz && chmod +x head)
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
export RAYKIN_COMMIT=07cae21
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv > "$OUT/gpu.txt"
MITSUBA_REPEATS=3 ASSETS=relb/assets RAYKIN_BIN=relb/head RAYKIN_INTEGRATOR=auto \
  timeout 230 bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
echo "side by side: $(elapsed) s"
grep -v warning /tmp/run.log | tail -n 30 > "$OUT/run-tail.log"
grep -h "traced by" /tmp/gpu-mitsuba/bench.log > "$OUT/traced-by.txt"
frames() {  # bench options...
  local w; w=$(mktemp -d)
  relb/head bench --suite full --parts frames --frames 30 "$@" --assets relb/assets --out "$w" --cache "$w/c" \
    >> /tmp/frames.log 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']: print(row['scene'], row['width'], row['spp_per_frame'], row['trace_ms_median'], row['integrator'], row.get('auto_trial_ms'))
" >> "$OUT/frames.txt"
}
echo "total: $(elapsed) s" | tee -a "$OUT/frames.txt"
cat "$OUT/frames.txt" "$OUT/traced-by.txt"
grep -A12 "time to equal error" "$OUT/summary.md" | head -20
