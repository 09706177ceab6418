#!/usr/bin/env bash
# The third device call of the seventeenth session: the Mitsuba 3 side by side (scripts/gpu-mitsuba.sh) with
# the head's binary (relm/head.xz, stripped release build) and raykin's integrator RAYKIN_INTEGRATOR (the A/B's
# winner). Carry .gl, relm (the binary; relm/assets with CornellBox, FlightHelmet, MetalRoughSpheresNoTextures)
# and .whl (Dr.Jit 1.5.0's cp312 wheel and mitsuba-strip.tar.xz from scripts/strip-mitsuba-wheel.sh).
set -u
start=$(date +%s)
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/drjit-*.whl || exit 1
tar -C /tmp -xJf .whl/mitsuba-strip.tar.xz
export PYTHONPATH=/tmp/site
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
(cd relm && xz -dkf head.xz && chmod +x head)
nvidia-smi --query-gpu=name,driver_version --format=csv > "$OUT/gpu.txt"
RAYKIN_COMMIT=${RAYKIN_COMMIT:-d22b3ff} ASSETS=relm/assets RAYKIN_BIN=relm/head bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
echo "side by side: $(( $(date +%s) - start )) s"
grep -v warning /tmp/run.log | tail -n 30 > "$OUT/run-tail.log"
grep -A12 "time to equal error" "$OUT/summary.md" | head -20
