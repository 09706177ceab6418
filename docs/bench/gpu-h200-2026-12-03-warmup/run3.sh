#!/usr/bin/env bash
# Device call 3 (H200): the error part on the Cornell box again with every repeat's per-frame trace times, and
# the clocks every 20 ms: where the slow frames of the curves come from.
set -u
OUT=${OUT:-gpu-out}; mkdir -p "$OUT"
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
(cd rel && xz -dkf raykin-new.xz && chmod +x raykin-new)
nvidia-smi --query-gpu=timestamp,clocks.sm,clocks.mem,power.draw,pstate,utilization.gpu,clocks_event_reasons.active --format=csv -lms 20 > "$OUT/clocks3.csv" 2>&1 &
smi=$!
for scene in cornell flight-helmet; do
  echo "$scene start $(date -u +%H:%M:%S.%N)" >> "$OUT/marks3.txt"
  rel/raykin-new bench --suite full --parts errors --scene $scene --curve "16 spp" --assets shared/assets \
    --out "$OUT/err-$scene" --cache /tmp/cache > "$OUT/err-$scene.log" 2>&1
  echo "$scene end $(date -u +%H:%M:%S.%N)" >> "$OUT/marks3.txt"
done
kill $smi
python3 - "$OUT" <<'PY'
import json, sys, glob
for f in sorted(glob.glob(sys.argv[1] + '/err-*/results.json')):
    r = json.load(open(f))
    for e in r['error_vs_time']:
        for c in e['curves']:
            for k, rep in enumerate(c['frame_trace_ms']):
                step = max(1, len(rep) // 32)
                print(e['scene'], c['name'][:12], 'repeat', k, [round(sum(rep[i:i+step]) / len(rep[i:i+step]), 2) for i in range(0, len(rep), step)])
PY
rm -rf "$OUT"/err-*/charts
tar -C "$OUT" -cJf /tmp/run3.tar.xz . && mv /tmp/run3.tar.xz "$OUT/"
