#!/usr/bin/env bash
# The Mitsuba 3 side by side (scripts/gpu-mitsuba.sh) with raykin's curves for both integrators against the same
# Mitsuba renders, so that the call needs no decision from call2.sh first: the megakernel's curves from
# gpu-mitsuba.sh itself, then the bench's error part again with `--integrator wavefront`. Binary relb/head.xz
# (the head's stripped release build) and relb/assets/{CornellBox,FlightHelmet,MetalRoughSpheresNoTextures};
# .whl holds Dr.Jit 1.5.0's cp312 wheel and mitsuba-strip.tar.xz (scripts/strip-mitsuba-wheel.sh). Carry
# [".gl", "relb", ".whl"]; RAYKIN_COMMIT names the binary's commit.
set -u
start=$(date +%s)
source scripts/gpu-unpack.sh
(cd relb && xz -dkf head.xz && chmod +x head)
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv > "$OUT/gpu.txt"
ASSETS=relb/assets RAYKIN_BIN=relb/head RAYKIN_INTEGRATOR=megakernel bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
echo "side by side: $(( $(date +%s) - start )) s"
grep -v warning /tmp/run.log | tail -n 30 > "$OUT/run-tail.log"
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
relb/head bench --suite full --scene cornell --scene spheres --scene flight-helmet --scene env-lit --scene many-lights \
  --assets relb/assets --parts errors --curve "16 spp" --integrator wavefront --mitsuba /tmp/mitsuba-export \
  --out /tmp/wave --cache /tmp/bench-cache > /tmp/wave.log 2>&1
echo "wavefront curves: $(( $(date +%s) - start )) s"
tar czf "$OUT/wavefront.tgz" -C /tmp/wave . /tmp/wave.log 2>/dev/null
cp /tmp/wave/summary.md "$OUT/summary-wavefront.md"
grep -A12 "time to equal error" "$OUT/summary.md" | head -20
grep -A12 "time to equal error" "$OUT/summary-wavefront.md" | head -20
