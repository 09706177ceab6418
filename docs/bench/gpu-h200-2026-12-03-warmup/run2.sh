#!/usr/bin/env bash
# Device call 2 (H200): run1.sh's part (2), the trace-time A/B of path regeneration, with the clocks logged.
set -u
OUT=${OUT:-gpu-out}; mkdir -p "$OUT/ab16" "$OUT/ab1"
nvidia-smi --query-gpu=timestamp,clocks.sm,clocks.mem,power.draw,pstate,utilization.gpu --format=csv -lms 100 > "$OUT/clocks2.csv" 2>&1 &
smi=$!
export SCENES="cornell flight-helmet spheres env-lit many-lights"
OUT="$OUT/ab16" FRAMES=20 BENCH_ARGS="--spp-per-frame 16 --width 1920 --height 1080" \
  bash scripts/gpu-ab-frames.sh 2 raykin-new:ab-shaders/sh-a raykin-new:ab-shaders/sh-b raykin-new
OUT="$OUT/ab1" BENCH_ARGS="--width 1920 --height 1080" \
  bash scripts/gpu-ab-frames.sh 2 raykin-new:ab-shaders/sh-a raykin-new:ab-shaders/sh-b raykin-new
kill $smi
tar -C "$OUT" -cJf /tmp/run2.tar.xz . && mv /tmp/run2.tar.xz "$OUT/"
