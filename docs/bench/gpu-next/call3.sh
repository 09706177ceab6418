#!/usr/bin/env bash
# The eighteenth session's third device call: `--integrator auto` (the faster form timed on each workload's
# first frames) against the two forms it chooses between, one binary (rel/auto.xz: the commit that adds auto,
# stripped release build), on the bench's static scenes, the crowd and the seed-like interior, rounds
# interleaved; the bench log's "traced by" lines say what auto chose and its trial's times. Carry [".gl", "rel"]
# (rel/assets as call2.sh).
set -u
start=$(date +%s)
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv > "$OUT/gpu.txt"
for round in 1 2; do
  ASSETS=rel/assets FRAMES=40 SCENES="cornell flight-helmet spheres env-lit crowd" timeout 200 \
    bash scripts/gpu-ab-frames.sh 1 auto,--integrator=auto auto,--integrator=megakernel auto,--integrator=wavefront \
    > "$OUT/ab-summary-$round.txt"
  echo "round $round static: $(( $(date +%s) - start )) s"
  START=$start BUDGET=500 bash scripts/gpu-seed-ab.sh 1 auto:auto auto:megakernel auto:wavefront > /dev/null
  echo "round $round seed: $(( $(date +%s) - start )) s"
done
cat "$OUT/ab.txt" "$OUT/seed.txt"
grep -h "traced by" "$OUT/bench.log" "$OUT/seed.log" > "$OUT/traced-by.txt"
cat "$OUT/traced-by.txt"
echo "total: $(( $(date +%s) - start )) s"
