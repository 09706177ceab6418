#!/usr/bin/env bash
# Nineteenth session, call 5 (relb/head.xz = 20adb82's stripped release build): how many sample lanes (the
# megakernel's invocations sharing a pixel's samples) pay, through RAYKIN_LANE_INVOCATIONS: at 960x540 (518 k
# pixels) 2^19 / 2^20 / 2^21 / 2^22 give 2 / 4 / 8 / 16 lanes, at 1920x1080 2^21 / 2^22 / 2^23 / 2^24 give 2 / 4 /
# 8 / 16; the megakernel's frame loop, 16 spp per frame, 20 frames, two rounds alternating -> lanes.txt. Carry
# [".gl", "relb"]; relb/assets holds CornellBox, FlightHelmet, MetalRoughSpheresNoTextures.
set -u
start=$(date +%s)
elapsed() { echo $(( $(date +%s) - start )); }
source scripts/gpu-unpack.sh
(cd relb && xz -dkf head.xz && chmod +x head)
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
export RAYKIN_COMMIT=20adb82
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv > "$OUT/gpu.txt"
frames() {  # invocations, width, height
  local w; w=$(mktemp -d)
  RAYKIN_LANE_INVOCATIONS=$1 relb/head bench --suite full --parts frames --frames 20 --integrator megakernel \
    --scene cornell --scene flight-helmet --scene spheres --scene env-lit --width "$2" --height "$3" \
    --spp-per-frame 16 --assets relb/assets --out "$w" --cache "$w/c" >> /tmp/frames.log 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']: print('invocations-$1', row['scene'], row['width'], row['spp_per_frame'], row['trace_ms_median'])
" >> "$OUT/lanes.txt"
}
for round in 1 2; do
  for n in 524288 1048576 2097152 4194304; do
    [ "$(elapsed)" -gt 220 ] && break 2
    frames "$n" 960 540
  done
  for n in 2097152 4194304 8388608 16777216; do
    [ "$(elapsed)" -gt 220 ] && break 2
    frames "$n" 1920 1080
  done
done
echo "total: $(elapsed) s" >> "$OUT/lanes.txt"
cat "$OUT/lanes.txt"
