#!/usr/bin/env bash
# The seventeenth session's second device call: after call.sh showed the wavefront forms tracing only camera rays
# on NVIDIA (their sizing kernels' pipeline layout left a gap where the scene's group is, which made the view's
# group incompatible for them; fixed in the commit this runs), the head's megakernel, the head's wavefront and the
# fused wavefront (wavefront-fused-head.patch: the fused form on d384a2c, with the same layout rule; the same
# image as the megakernel bit for bit and clean under the validation layer on lavapipe) on the bench's static
# scenes and the crowd; then the seed-like interior. Binaries: rel/head.xz (the head's release build, stripped)
# and rel/fused.xz (the patch applied); assets as call.sh (its header has the build recipe). Carry [".gl", "rel"].
set -u
start=$(date +%s)
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv > "$OUT/gpu.txt"
# Rounds interleaved (static scenes, then the seed-like interior, twice) so that a call cut short by the device
# budget still brings one complete round back.
for round in 1 2; do
  ASSETS=rel/assets FRAMES=40 SCENES="cornell flight-helmet spheres env-lit crowd" timeout 200 \
    bash scripts/gpu-ab-frames.sh 1 head head,--integrator=wavefront fused,--integrator=wavefront > "$OUT/ab-summary-$round.txt"
  echo "round $round static: $(( $(date +%s) - start )) s"
  START=$start BUDGET=540 bash scripts/gpu-seed-ab.sh 1 head:megakernel head:wavefront fused:wavefront > /dev/null
  echo "round $round seed: $(( $(date +%s) - start )) s"
done
cat "$OUT/ab.txt" "$OUT/seed.txt"
grep -v warning "$OUT/bench.log" | grep "ms/frame" > "$OUT/frames.txt"
echo "total: $(( $(date +%s) - start )) s"
