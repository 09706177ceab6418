#!/usr/bin/env bash
# Device call (ab-2): which change moved the trace time: the new binary with 2bed230's tlas.wgsl or bvh2.wgsl put
# back through RAYKIN_SHADER_DIR (rel/sd_*), beside both binaries as they are; two rounds.
exec bash scripts/gpu-ab-frames.sh 2 raykin-old raykin-new raykin-new:rel/sd_tlasold raykin-new:rel/sd_bvhold
