#!/usr/bin/env bash
# The Mitsuba 3 side by side (scripts/gpu-mitsuba.sh) for the next device call, after call2.sh has said which
# integrator wins: the head's binary (rel/head.xz, stripped release build) with raykin's integrator
# RAYKIN_INTEGRATOR. The working tree's limit (64 MiB with the tracked 26 MB) leaves room for rel/ holding only
# head.xz and rel/assets/{CornellBox,FlightHelmet,MetalRoughSpheresNoTextures}, .gl, and .whl (Dr.Jit 1.5.0's
# cp312 wheel and mitsuba-strip.tar.xz from scripts/strip-mitsuba-wheel.sh). Carry [".gl", "rel", ".whl"].
set -u
start=$(date +%s)
source scripts/gpu-unpack.sh head
nvidia-smi --query-gpu=name,driver_version --format=csv > "$OUT/gpu.txt"
ASSETS=rel/assets RAYKIN_BIN=rel/head bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
echo "side by side: $(( $(date +%s) - start )) s"
grep -v warning /tmp/run.log | tail -n 30 > "$OUT/run-tail.log"
grep -A12 "time to equal error" "$OUT/summary.md" | head -20
