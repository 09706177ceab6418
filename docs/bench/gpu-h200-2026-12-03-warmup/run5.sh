#!/usr/bin/env bash
# Device call 5 (H200): trace time of three kernel variants against the built-in kernel (aee5f83's binary),
# through RAYKIN_SHADER_DIR, alternating twice, at 1 and 16 spp per frame, 1920x1080: `wrap` = bilinear texture
# lookups wrap each coordinate once (4 wraps instead of 8; kept if it wins), and two diagnostics that change the
# image: `noaov` = the path records no denoiser AOVs (the registers they hold), `nearest` = every texture read
# nearest-neighbour (what filtering costs). Carry .gl, rel and ab-shaders (made by make_variants.py from aee5f83's shaders, see
# BENCHMARKS.md).
set -u
OUT=${OUT:-gpu-out}; mkdir -p "$OUT/ab16" "$OUT/ab1"
export SCENES="flight-helmet cornell spheres env-lit"
V="raykin-new raykin-new:ab-shaders/wrap raykin-new:ab-shaders/noaov raykin-new:ab-shaders/nearest"
OUT="$OUT/ab16" FRAMES=20 BENCH_ARGS="--spp-per-frame 16 --width 1920 --height 1080" bash scripts/gpu-ab-frames.sh 2 $V
OUT="$OUT/ab1" BENCH_ARGS="--width 1920 --height 1080" bash scripts/gpu-ab-frames.sh 2 $V
