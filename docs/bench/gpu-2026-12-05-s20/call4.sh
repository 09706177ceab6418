#!/usr/bin/env bash
# Twentieth session, call 4: call3.sh again, the same binary (07cae21's code), on the next machine lent, for the
# call-to-call spread of the side by side's ratios (Mitsuba's own samples/s moved 0.8-1.1x between earlier calls).
set -u
start=$(date +%s)
elapsed() { echo $(( $(date +%s) - start )); }
source scripts/gpu-unpack.sh
(cd relb && xz -dkf head.xz && chmod +x head)
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
export RAYKIN_COMMIT=07cae21
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv > "$OUT/gpu.txt"
MITSUBA_REPEATS=1 ASSETS=relb/assets RAYKIN_BIN=relb/head RAYKIN_INTEGRATOR=auto \
  timeout 420 bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
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
[ "$(elapsed)" -lt 500 ] && frames --scene cornell --scene flight-helmet --scene spheres --scene env-lit --width 960 --height 540 --spp-per-frame 16
[ "$(elapsed)" -lt 540 ] && frames --scene seed-interior --width 2560 --height 1440
echo "total: $(elapsed) s" | tee -a "$OUT/frames.txt"
cat "$OUT/frames.txt" "$OUT/traced-by.txt"
grep -A12 "time to equal error" "$OUT/summary.md" | head -20
