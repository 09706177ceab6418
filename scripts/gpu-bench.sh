#!/usr/bin/env bash
# The whole device-side GPU run in one command (issue 7). Run it on the lent GPU machine from the repo root, with
# the release binary carried at rel/raykin and the Vulkan loader debs at .gl/ (see ../.library/device/README.md):
#   for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig; scripts/gpu-bench.sh $OUT
# Writes OUT/gpu-bench.log, OUT/results.json / results.csv (full suite: 3 scenes x 1080p/1440p, 300 frames) and
# OUT/crowd.json (the animated crowd through the frame loop, GPU deformation) and OUT/crowd-cpu/crowd.json (CPU). ASSETS must hold CornellBox, FlightHelmet,
# MetalRoughSpheresNoTextures, CesiumMan and Fox (copies of ../shared/assets).
set -uo pipefail
out="${1:-gpu-out}"
mkdir -p "$out"
bin="${RAYKIN_BIN:-rel/raykin}"
if ! "$bin" --version >/dev/null 2>&1; then echo "no raykin binary at $bin" >&2; exit 1; fi
if [ -z "${VK_DRIVER_FILES:-}" ] && [ -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ]; then
  export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
fi
export RAYKIN_COMMIT="${RAYKIN_COMMIT:-$(git rev-parse --short HEAD 2>/dev/null || echo unknown)}"
{
  nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null || true
  "$bin" bench --suite full --assets "${ASSETS:-shared/assets}" --out "$out"
  # The crowd with GPU skinning + refit (the default on a real GPU), then the CPU path for comparison.
  "$bin" bench --crowd --suite full --deform gpu --assets "${ASSETS:-shared/assets}" --out "$out"
  "$bin" bench --crowd --suite full --deform cpu --assets "${ASSETS:-shared/assets}" --out "$out/crowd-cpu"
  "$bin" render "${ASSETS:-shared/assets}/CornellBox/CornellBox.glb" --look-from=-278,273,800 --look-at=-278,273,0 \
    --fov 39.3077 --env 0,0,0 --width 1024 --height 1024 --spp 1024 --out "$out/cornell-1024spp.png" --report "$out/cornell-render.json"
} 2>&1 | tee "$out/gpu-bench.log"
