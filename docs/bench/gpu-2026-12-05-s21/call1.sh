#!/usr/bin/env bash
# Twenty-first session, call 1 (relb/head.xz = 1ec8abb + the engine's kernels compiled without naga's loop bounding
# and integer-division guards, `RAYKIN_SHADER_CHECKS_ALL` restoring them). Three parts, each with its own file:
# 1. a probe: whether Nsight Compute (ncu) reads the counters of wgpu's Vulkan compute kernels -> ncu.txt;
# 2. the runtime checks A/B: the bench's frame loop (960x540, 16 spp per frame, 24 frames, auto) with and without
#    the checks, alternating, two rounds -> checks.txt;
# 3. the twentieth session's call 6 (FlightHelmet's megakernel by ablation) -> frames.txt.
# Carry [".gl", "relb"].
set -u
source scripts/gpu-unpack.sh
if command -v ncu >/dev/null 2>&1 || ls /opt/nvidia/nsight-compute/*/ncu >/dev/null 2>&1; then
  NCU=$(command -v ncu || ls /opt/nvidia/nsight-compute/*/ncu | head -1)
  echo "ncu: $NCU" >> "$OUT/ncu.txt"
  timeout 60 "$NCU" --clock-control none --target-processes all --launch-count 6 \
    relb/head render relb/assets/CornellBox/CornellBox.glb --width 256 --height 256 --spp 16 --integrator wavefront \
    --out /tmp/ncu.exr >> "$OUT/ncu.txt" 2>&1
  echo "ncu rc $?" >> "$OUT/ncu.txt"
fi
tail -30 "$OUT/ncu.txt"
checks() {  # label, env assignment
  local w; w=$(mktemp -d)
  env "$2" relb/head bench --suite full --parts frames --frames 24 --scene cornell --scene flight-helmet \
    --scene spheres --width 960 --height 540 --spp-per-frame 16 --assets relb/assets --out "$w" --cache "$w/c" \
    > "$w/log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']: print('$1', row['scene'], row['width'], row['spp_per_frame'], row['trace_ms_median'], row['integrator'])
" >> "$OUT/checks.txt" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
for round in 1 2; do
  checks fewer RAYKIN_NONE=1
  checks all RAYKIN_SHADER_CHECKS_ALL=1
done
echo "checks: $(elapsed) s" | tee -a "$OUT/checks.txt"
cat "$OUT/checks.txt"
bash docs/bench/gpu-2026-12-05-s20/call6.sh
