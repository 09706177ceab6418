#!/usr/bin/env bash
# The whole device-side GPU run in one command (issue 7). Run it on the lent GPU machine from the repo root, with
# the release binary carried at rel/raykin and the Vulkan loader debs at .gl/ (see ../.library/device/README.md):
#   for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig; scripts/gpu-bench.sh $OUT
# `raykin bench --suite full` (4 scenes incl. the animated crowd at 1920x1080 and 2560x1440, 300 frames; error vs
# time; BVH presets; refit vs rebuild; scaling), the crowd again with CPU skinning + refit, the crowd through the
# viewer's offscreen frame loop (UI pass included) at 1920x1080 and 2560x1440, plus one converged Cornell render.
# At most 8 files land in OUT (the device tool returns 8): gpu-bench.log, results.json, results.csv, summary.md,
# bundle.tar (charts/*.png, curves.csv, results-crowd-cpu.json, view-crowd-1080p.json, view-crowd-1440p.json),
# cornell-1024spp.png, cornell-render.json. ASSETS must hold CornellBox, FlightHelmet,
# MetalRoughSpheresNoTextures, CesiumMan, Fox and DamagedHelmet (copies of ../shared/assets).
# BENCH_ARGS adds arguments to the bench (e.g. "--parts frames --parts errors" to split the run over two calls);
# CORNELL_RENDER=0 skips the converged render (for a dry run of this script on a CPU adapter).
set -uo pipefail
# shellcheck source=scripts/gpu-common.sh
. "$(dirname "$0")/gpu-common.sh"
work="$(mktemp -d)"
{
  nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null || true
  # shellcheck disable=SC2086
  "$bin" bench --suite full --assets "$assets" --out "$work/bench" --cache "$work/cache" ${BENCH_ARGS:-}
  cp "$work/bench/results.json" "$work/bench/results.csv" "$work/bench/summary.md" "$out/" 2>/dev/null
  # The crowd again with CPU skinning + refit (the full suite used the GPU passes), for the comparison.
  "$bin" bench --suite full --scene crowd --parts frames --deform cpu --assets "$assets" --out "$work/crowd-cpu"
  cp "$work/crowd-cpu/results.json" "$work/bench/results-crowd-cpu.json" 2>/dev/null
  # The interactive path: the viewer's frame loop without a window, 300 frames, per-pass times.
  for size in 1920x1080 2560x1440; do
    "$bin" view crowd --assets "$assets" --offscreen --frames 300 --image-size "$size" --spp-per-frame 1 \
      --max-depth 6 --no-settings --report "$work/bench/view-crowd-${size#*x}p.json"
  done
  (cd "$work/bench" && tar -cf "$out/bundle.tar" charts curves.csv results-crowd-cpu.json view-crowd-*.json) 2>/dev/null
  if [ "${CORNELL_RENDER:-1}" = 1 ]; then
    "$bin" render "$assets/CornellBox/CornellBox.glb" --look-from=-278,273,800 --look-at=-278,273,0 --fov 39.3077 \
      --env 0,0,0 --width 1024 --height 1024 --spp 1024 --out "$out/cornell-1024spp.png" --report "$out/cornell-render.json"
  fi
} 2>&1 | grep --line-buffered -v "zero-area triangles dropped" | tee "$out/gpu-bench.log"
rm -rf "$work"
