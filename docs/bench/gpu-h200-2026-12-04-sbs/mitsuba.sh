#!/usr/bin/env bash
# Device call: the Mitsuba 3 side by side (scripts/gpu-mitsuba.sh) at e9c9e11 (binary rel/raykin-z.xz, that tree
# at opt-level 3, stripped; the trace kernels are those of 0af83a4 plus the read_* functions and the texel
# helpers, which GPUs do not use). Carry .gl, rel (the binary; rel/assets with CornellBox, FlightHelmet and
# MetalRoughSpheresNoTextures) and .whl (Dr.Jit 1.5.0's cp312 wheel and mitsuba-strip.tar.xz, made by
# scripts/strip-mitsuba-wheel.sh from Mitsuba 3.9.1's cp312 wheel).
set -u
start=$(date +%s)
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/drjit-*.whl || exit 1
tar -C /tmp -xJf .whl/mitsuba-strip.tar.xz
export PYTHONPATH=/tmp/site
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
(cd rel && xz -dkf raykin-z.xz && chmod +x raykin-z)
RAYKIN_COMMIT=e9c9e11 ASSETS=rel/assets RAYKIN_BIN=rel/raykin-z bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
echo "side by side: $(( $(date +%s) - start )) s"
grep -v warning /tmp/run.log | tail -n 30 > "$OUT/run-tail.log"
grep -A12 "time to equal error" "$OUT/summary.md" | head -20
