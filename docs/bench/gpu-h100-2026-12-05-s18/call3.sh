#!/usr/bin/env bash
# The eighteenth session's last device call (what was left of its budget): the Mitsuba 3 side by side on the two
# scenes whose target is missed
# (scripts/gpu-mitsuba.sh) with raykin's default, `--integrator auto`, and waves of several samples per pixel
# (relb/multi.xz = 5dc83ad), then, as time allows, the frame loop at the error part's size and curve (960x540,
# 16 spp per frame) and the seed-like interior with auto and each form. Carry [".gl", "relb", ".whl"];
# relb/assets holds CornellBox, FlightHelmet, MetalRoughSpheresNoTextures, CesiumMan, Fox.
set -u
start=$(date +%s)
source scripts/gpu-unpack.sh
(cd relb && xz -dkf multi.xz && chmod +x multi)
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv > "$OUT/gpu.txt"
MITSUBA_SCENES="cornell flight-helmet" MITSUBA_REPEATS=1 ASSETS=relb/assets RAYKIN_BIN=relb/multi RAYKIN_INTEGRATOR=auto \
  RAYKIN_COMMIT=5dc83ad timeout 250 bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
echo "side by side: $(( $(date +%s) - start )) s"
grep -v warning /tmp/run.log | tail -n 30 > "$OUT/run-tail.log"
grep -h "traced by" /tmp/gpu-mitsuba/bench.log > "$OUT/traced-by.txt"
frames() {  # integrator, extra bench options...
  local w; w=$(mktemp -d); local integrator=$1; shift
  relb/multi bench --suite full --parts frames --frames 30 --integrator "$integrator" "$@" --assets relb/assets \
    --out "$w" --cache "$w/c" >> /tmp/frames.log 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']: print('$integrator', row['scene'], row['width'], row['spp_per_frame'], row['trace_ms_median'], row['integrator'], row.get('auto_trial_ms'))
" >> "$OUT/frames.txt"
}
for integrator in megakernel wavefront auto; do
  [ $(( $(date +%s) - start )) -gt 300 ] && break
  frames "$integrator" --scene cornell --scene flight-helmet --scene spheres --scene env-lit --width 960 --height 540 --spp-per-frame 16
done
for integrator in megakernel wavefront auto; do
  [ $(( $(date +%s) - start )) -gt 330 ] && break
  frames "$integrator" --scene seed-interior --width 2560 --height 1440
done
grep -h "traced by" /tmp/frames.log >> "$OUT/traced-by.txt"
cat "$OUT/frames.txt" "$OUT/traced-by.txt"
grep -A10 "time to equal error" "$OUT/summary.md" | head -12
echo "total: $(( $(date +%s) - start )) s"
