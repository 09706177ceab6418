#!/usr/bin/env bash
# Second of two device calls: OIDN per real-time frame (RealtimeSettings::oidn) against the a-trous filter it
# replaces, on the lent H200 (binary rel/raykin-o.xz: this commit's tree at opt-level 3, stripped; rel/assets holds
# CornellBox, CesiumMan and Fox). OIDN's CUDA libraries travel in two halves as in
# ../gpu-h200-2026-12-04-split/gains.sh: the first call (carry .oidnpack-a) ran `cp .oidnpack-a/oidnpart.00 /root/`,
# this one carries .gl, .oidnpack-b and rel.
# 1. The viewer's offscreen frame loop in real-time mode on the crowd, 150 frames at 2560x1440 and 1920x1080:
#    the a-trous filter (--frame-oidn off) and OIDN per frame at fast, balanced and high (its wall time per frame
#    in the report's oidn_per_frame).
# 2. `raykin bench --parts motion` on the interior and the crowd at 1280x720, 60 frames: every method's settled
#    relMSE and FLIP against converged poses (1024 spp), with the OIDN curves.
set -u
[ -f /root/oidnpart.00 ] || { echo "no /root/oidnpart.00: the machine was not the warm one"; exit 3; }
mkdir -p /root/oidn/lib && cat /root/oidnpart.00 .oidnpack-b/oidnpart.01 | xz -d | tar x -C /root/oidn/lib
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json RAYKIN_OIDN_DIR=/root/oidn/lib
(cd rel && xz -dkf raykin-o.xz && chmod +x raykin-o)
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
w=$(mktemp -d)
mkdir -p "$w/views"
for size in 2560x1440 1920x1080; do
  for v in "off balanced" "always fast" "always balanced" "always high"; do
    set -- $v
    [ "$size" = 1920x1080 ] && [ "$2" != balanced ] && continue
    name="crowd-$size-$1-$2"
    timeout 90 rel/raykin-o view crowd --assets rel/assets --offscreen --frames 150 --image-size "$size" \
      --spp-per-frame 1 --max-depth 6 --no-settings --mode realtime --frame-oidn "$1" --frame-oidn-quality "$2" \
      --report "$w/views/$name.json" > "$w/views/$name.log" 2>&1
    echo "$name rc $?: $(grep -h 'offscreen' "$w/views/$name.log" | tail -n 1)"
    python3 -c "import json,sys; r=json.load(open(sys.argv[1])); o=r['oidn_per_frame']; m=lambda x: x and x['median']; print('  frame', m(r['cpu_ms']['frame']), 'gpu total', m(r['gpu_ms']['realtime_frame_total']), 'oidn', o['frames'], m(o['wall_ms']), o['device'], o['failed'])" "$w/views/$name.json" 2>&1
  done
done
(cd "$w" && tar -cf "$OUT/views.tar" views)
timeout 360 rel/raykin-o bench --suite full --parts motion --scene interior --scene crowd --frames 60 \
  --width 1280 --height 720 --assets rel/assets --out "$w/m" --cache "$w/c" > "$w/motion.log" 2>&1
echo "motion rc $?"
cp "$w/m/results.json" "$OUT/motion-results.json"; cp "$w/m/summary.md" "$OUT/motion-summary.md"
(cd "$w/m" && tar -cf "$OUT/charts.tar" charts) 2>/dev/null
grep -v "warning" "$w/motion.log" | grep "motion" | tail -n 40
