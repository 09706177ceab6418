#!/usr/bin/env bash
# The next device call's plan (written 2026-12-05, sixteenth session, no device lent): d0f86a6's megakernel
# (`start`: before the sixteenth session's padded positions and environment texels and the compiled-out in-cell
# sampling, none measured on a GPU), the head's megakernel, the wavefront form shipped since d0f86a6 (the first
# bounce as one kernel, extend/shade split after it) and the wavefront as one kernel per bounce
# (docs/bench/lavapipe-2026-12-05-fused/wavefront-fused.patch), one call, alternating, two rounds; then the
# seed-like interior with the head's three.
# Set-up on the 2-core machine (from the repository root):
#   git worktree add ../start d0f86a6 && (cd ../start && cargo build --release -p raykin) \
#     && strip -o rel/start ../start/target/release/raykin && xz -T2 -6 -f rel/start   (then remove the worktree)
#   cargo build --release -p raykin && strip -o rel/head target/release/raykin && xz -T2 -6 -f rel/head
#   git apply docs/bench/lavapipe-2026-12-05-fused/wavefront-fused.patch && cargo build --release -p raykin \
#     && strip -o rel/fused target/release/raykin && xz -T2 -6 -f rel/fused && git apply -R docs/bench/lavapipe-2026-12-05-fused/wavefront-fused.patch
#   mkdir -p rel/assets && cp -r ../shared/assets/{CornellBox,FlightHelmet,MetalRoughSpheresNoTextures,CesiumMan,Fox} rel/assets/
#   (.gl: the Vulkan loader recipe of ../.library/device/README.md)
# Run: bash docs/bench/gpu-next/call.sh with carry [".gl", "rel"].
set -u
start=$(date +%s)
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv > "$OUT/gpu.txt"
ASSETS=rel/assets FRAMES=40 SCENES="cornell flight-helmet spheres env-lit crowd" timeout 400 \
  bash scripts/gpu-ab-frames.sh 2 start head head,--integrator=wavefront fused,--integrator=wavefront > "$OUT/ab-summary.txt"
cat "$OUT/ab-summary.txt"
echo "static scenes: $(( $(date +%s) - start )) s"
START=$start bash scripts/gpu-seed-ab.sh 2 head:megakernel head:wavefront fused:wavefront
echo "total: $(( $(date +%s) - start )) s"
