#!/usr/bin/env bash
# Device call: texture wrapping once per axis (t2 of the sixth session, docs/bench/gpu-h200-2026-12-03-leaf/
# variants/t2-texture.wgsl, unchanged file since) retried on top of the merged static tree: then it was 0.89-0.91x
# on FlightHelmet but 1.055x on the crowd, a register-allocation effect of the alpha test inlined in the
# traversal loops. Binary of 64c8d5b (rel/raykin-h.xz) as is and with RAYKIN_SHADER_DIR=rel/var/t2 (the current
# shaders with t2's texture.wgsl), alternating twice on every bench scene. Carry .gl and rel.
set -u
ASSETS=rel/assets SCENES="cornell flight-helmet spheres env-lit many-lights crowd seed-interior" bash scripts/gpu-ab-frames.sh 2 \
  raykin-h raykin-h:rel/var/t2
