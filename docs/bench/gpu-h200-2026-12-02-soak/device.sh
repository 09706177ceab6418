#!/usr/bin/env bash
# Device call: the viewer's offscreen frame loop on the crowd at 1440p (real-time mode, the default) for as long
# as one device command allows; resident memory (process) and GPU memory (nvidia-smi) sampled every 10 s.
set -u
for f in .gl/*.deb; do dpkg -x $f / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
(cd rel && xz -dkf raykin.xz && chmod +x raykin)
FRAMES=${FRAMES:-18000}
rel/raykin view crowd --assets shared/assets --offscreen --frames "$FRAMES" --image-size 2560x1440 \
  --spp-per-frame 1 --max-depth 6 --no-settings --report "$OUT/soak.json" > "$OUT/soak.log" 2>&1 &
pid=$!
start=$(date +%s)
echo "t_s,rss_kib,gpu_used_mib" > "$OUT/memory.csv"
while kill -0 $pid 2>/dev/null; do
  rss=$(awk '/VmRSS/ {print $2}' /proc/$pid/status 2>/dev/null)
  gpu=$(nvidia-smi --query-gpu=memory.used --format=csv,noheader,nounits 2>/dev/null | head -1)
  echo "$(( $(date +%s) - start )),$rss,$gpu" >> "$OUT/memory.csv"
  sleep 10
done
wait $pid; echo "exit $?"
tail -3 "$OUT/soak.log"; head -3 "$OUT/memory.csv"; tail -3 "$OUT/memory.csv"
