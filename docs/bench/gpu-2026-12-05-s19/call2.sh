#!/usr/bin/env bash
# Nineteenth session, call 2 (relb/head.xz = abb3234's stripped release build): the sample lanes as chosen now
# (the fewest giving 4 M invocations: 16 at 960x540, 4 at 1080p; sums through 1 KB of workgroup memory) against
# the one-invocation loop (RAYKIN_SAMPLE_LANES=off), and the wavefront with its new default waves (8.4 M paths),
# the frame loop at 960x540 and 1080p, 16 spp per frame, two rounds alternating -> frames.txt; then the Mitsuba 3
# side by side (scripts/gpu-mitsuba.sh) on all five static scenes with the default `--integrator auto`, one
# Mitsuba render per count. Carry [".gl", "relb", ".whl"]; relb/assets holds CornellBox, FlightHelmet,
# MetalRoughSpheresNoTextures; .whl Dr.Jit 1.5.0's cp312 wheel and `KEEP_DATA= bash
# scripts/strip-mitsuba-wheel.sh mitsuba-3.9.1-*.whl .whl/mitsuba-strip.tar.xz`.
set -u
start=$(date +%s)
elapsed() { echo $(( $(date +%s) - start )); }
source scripts/gpu-unpack.sh
(cd relb && xz -dkf head.xz && chmod +x head)
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
export RAYKIN_COMMIT=abb3234
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv > "$OUT/gpu.txt"
frames() {  # label, integrator, bench options... (the label's words are the environment: lanes-on, waves-N)
  local w; w=$(mktemp -d); local label=$1 integrator=$2; shift 2
  local lanes=on; [[ $label == *lanes-off* ]] && lanes=off
  local waves=2097152; [[ $label =~ waves-([0-9]+) ]] && waves=${BASH_REMATCH[1]}
  RAYKIN_SAMPLE_LANES=$lanes RAYKIN_WAVE_PATHS=$waves relb/head bench --suite full --parts frames --frames 30 \
    --integrator "$integrator" "$@" --assets relb/assets --out "$w" --cache "$w/c" >> /tmp/frames.log 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']: print('$label', row['scene'], row['width'], row['spp_per_frame'], row['trace_ms_median'], row['integrator'])
" >> "$OUT/frames.txt"
}
scenes=(--scene cornell --scene flight-helmet --scene spheres --scene env-lit)
for round in 1 2; do
  for size in "960 540" "1920 1080"; do
    set -- $size
    for form in "lanes-off megakernel" "lanes-on megakernel" "waves-8388608 wavefront"; do
      [ "$(elapsed)" -gt 200 ] && break 3
      frames $form "${scenes[@]}" --width "$1" --height "$2" --spp-per-frame 16
    done
  done
done
echo "frames: $(elapsed) s" | tee -a "$OUT/frames.txt"
MITSUBA_REPEATS=1 ASSETS=relb/assets RAYKIN_BIN=relb/head RAYKIN_INTEGRATOR=auto \
  timeout $(( 585 - $(elapsed) )) bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
echo "side by side: $(elapsed) s"
grep -v warning /tmp/run.log | tail -n 30 > "$OUT/run-tail.log"
grep -h "traced by" /tmp/gpu-mitsuba/bench.log > "$OUT/traced-by.txt"
cat "$OUT/frames.txt"
grep -A12 "time to equal error" "$OUT/summary.md" | head -20
