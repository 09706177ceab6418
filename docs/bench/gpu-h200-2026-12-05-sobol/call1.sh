#!/usr/bin/env bash
# Device call 1: the Mitsuba side by side at the head (68fb315, independent sampler in both), then raykin's
# error curves with the Owen-scrambled Sobol' sampler (sobol/sampler.wgsl through RAYKIN_SHADER_DIR) against
# the same Mitsuba renders.
set -u
start=$(date +%s)
source scripts/gpu-unpack.sh head
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv > "$OUT/gpu.txt"
export RAYKIN_COMMIT=68fb315 ASSETS=rel/assets RAYKIN_BIN=rel/head
timeout 400 bash scripts/gpu-mitsuba.sh "$OUT/a" > /tmp/run.log 2>&1
echo "side by side: $(( $(date +%s) - start )) s"
grep -v warning /tmp/run.log | tail -n 30 > "$OUT/run-tail.log"
grep -A12 "time to equal error" "$OUT/a/summary.md" | head -16
left=$(( 575 - ($(date +%s) - start) ))
echo "sobol run with ${left} s left"
RAYKIN_SHADER_DIR=sobol timeout "$left" rel/head bench --suite full --scene cornell --scene spheres --scene flight-helmet \
  --scene env-lit --assets rel/assets --parts errors --curve "16 spp" --mitsuba /tmp/mitsuba-export --out /tmp/sob \
  --cache /tmp/bench-cache-sobol > /tmp/sob.log 2>&1
tar czf "$OUT/sobol.tgz" -C /tmp sob sob.log
cp /tmp/sob/summary.md "$OUT/sobol-summary.md" 2>/dev/null
grep -A12 "time to equal error" "$OUT/sobol-summary.md" | head -16
echo "total: $(( $(date +%s) - start )) s"
