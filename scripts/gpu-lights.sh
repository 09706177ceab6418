#!/usr/bin/env bash
# Issue 15's GPU measurements in one device call. Run from the repo root on the lent GPU machine, with the release
# binary carried at rel/raykin and the Vulkan loader debs at .gl/ (../.library/device/README.md):
#   for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig; scripts/gpu-lights.sh $OUT
# 1. `raykin bench --parts errors` on the environment-lit scene (env-lit: tests/reference/lights/envmap.gltf under
#    a 64x33 map whose sun is one texel of radiance ~900) and on 400 emitters over a floor (many-lights): error vs
#    trace time per curve; results.json gives each curve's ms_to_rel_mse_0_01, so the default (NEE + MIS with the
#    importance-sampled map) against "NEE/MIS off (BRDF sampling only)" is the >= 5x target, and the default
#    light sampler against the other one ("power light sampler") says which wins with hundreds of emitters.
# 2. Converged 1024x1024 renders: the shipped Cornell box (near-emitter fix), the env-lit scene, daylight
#    (--sun-sky) and depth of field on the lit test scene.
# At most 8 files land in OUT: gpu-lights.log, results.json, summary.md, bundle.tar (charts, curves.csv),
# cornell.png, env-lit.png, sun-sky.png, dof.png. ASSETS must hold CornellBox (a copy of ../shared/assets).
# Expected wall time on an H200: about 4-6 minutes.
set -uo pipefail
# shellcheck source=scripts/gpu-common.sh
. "$(dirname "$0")/gpu-common.sh"
lights=tests/reference/lights
work="$(mktemp -d)"
{
  nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null || true
  # shellcheck disable=SC2086
  "$bin" bench --suite full --parts errors --scene env-lit --scene many-lights --assets "$assets" \
    --out "$work/bench" --cache "$work/cache" ${BENCH_ARGS:-}
  cp "$work/bench/results.json" "$work/bench/summary.md" "$out/" 2>/dev/null
  (cd "$work/bench" && tar -cf "$out/bundle.tar" charts curves.csv) 2>/dev/null
  if [ "${RENDERS:-1}" = 1 ]; then
    "$bin" render "$assets/CornellBox/CornellBox.glb" --look-from=-278,273,800 --look-at=-278,273,0 --fov 39.3077 \
      --env 0,0,0 --width 1024 --height 1024 --spp 1024 --out "$out/cornell.png"
    "$bin" render "$lights/envmap.gltf" --look-from 0,2.2,5 --look-at 0,0.6,0 --fov 40 \
      --env-map "$lights/sunny_64x33.exr" --env-rotation 30 --width 1024 --height 1024 --spp 1024 \
      --out "$out/env-lit.png"
    "$bin" render "$lights/envmap.gltf" --look-from 0,2.2,5 --look-at 0,0.6,0 --fov 40 \
      --sun-sky 25,60 --exposure -5 --width 1024 --height 1024 --spp 1024 --out "$out/sun-sky.png"
    "$bin" render "$lights/point.gltf" --look-from 0,2.2,5 --look-at 0,0.6,0 --fov 40 --env 0.05,0.05,0.05 \
      --aperture 0.08 --focus-distance 5.2 --width 1024 --height 1024 --spp 1024 --out "$out/dof.png"
  fi
} 2>&1 | tee "$out/gpu-lights.log"
rm -rf "$work"
