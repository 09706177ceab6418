#!/usr/bin/env bash
# Device call 6 (H200): the trace kernel without the denoisers' inputs where nothing reads them (PATH_AOVS; the
# bench's renders keep none) against aee5f83, two binaries alternating three times, 1 and 16 spp per frame.
set -u
OUT=${OUT:-gpu-out}; mkdir -p "$OUT/ab16" "$OUT/ab1"
export SCENES="flight-helmet cornell spheres env-lit many-lights"
OUT="$OUT/ab16" FRAMES=20 BENCH_ARGS="--spp-per-frame 16 --width 1920 --height 1080" bash scripts/gpu-ab-frames.sh 3 raykin-new raykin-aov
OUT="$OUT/ab1" BENCH_ARGS="--width 2560 --height 1440" bash scripts/gpu-ab-frames.sh 3 raykin-new raykin-aov
