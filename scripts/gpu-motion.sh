#!/usr/bin/env bash
# The real-time path's GPU run in one command (issue 13). Run it on the lent GPU machine from the repo root, with
# the release binary carried at rel/raykin and the Vulkan loader debs at .gl/ (see ../.library/device/README.md):
#   for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig; scripts/gpu-motion.sh $OUT
# 1. `raykin bench --suite full --parts motion`: the crowd and the animated interior at 2560x1440, 120 frames at
#    1/60 s, four methods (restart + spatial, + reprojection, + gradients, + ReSTIR DI): relMSE/FLIP of the
#    displayed frame against converged poses (1024 spp), per-pass GPU times, disoccluded-band error, lamp lag.
# 2. The viewer's offscreen frame loop in real-time mode on the crowd at 2560x1440 (per-pass times, UI included).
# At most 8 files land in OUT: gpu-motion.log, results.json, motion.csv, summary.md, charts.tar (motion-*.png),
# view-crowd-realtime-1440p.json. ASSETS must hold CornellBox, CesiumMan and Fox (copies of ../shared/assets).
# MOTION_ARGS adds arguments to the bench (e.g. "--scene interior --frames 60" to split the run over two calls).
set -uo pipefail
# shellcheck source=scripts/gpu-common.sh
. "$(dirname "$0")/gpu-common.sh"
work="$(mktemp -d)"
{
  nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null || true
  # shellcheck disable=SC2086
  "$bin" bench --suite full --parts motion --assets "$assets" --out "$work/bench" --cache "$work/cache" ${MOTION_ARGS:-}
  cp "$work/bench/results.json" "$work/bench/motion.csv" "$work/bench/summary.md" "$out/" 2>/dev/null
  (cd "$work/bench" && tar -cf "$out/charts.tar" charts) 2>/dev/null
  "$bin" view crowd --assets "$assets" --offscreen --frames 300 --image-size 2560x1440 --spp-per-frame 1 \
    --max-depth 6 --no-settings --mode realtime --report "$out/view-crowd-realtime-1440p.json"
} 2>&1 | grep --line-buffered -v "zero-area triangles dropped" | tee "$out/gpu-motion.log"
rm -rf "$work"
