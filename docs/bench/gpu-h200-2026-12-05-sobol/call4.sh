#!/usr/bin/env bash
# Device call 4 (d12e333's binary `final`): the sampler's values randomised by a digital shift (xor) instead of an
# Owen scramble (sobol/xor/sampler.wgsl through RAYKIN_SHADER_DIR; the index shuffle unchanged). Trace time per
# frame, final / xor / old (68fb315's sampler, sobol/old), two alternating rounds; then the error curves of
# FlightHelmet and env-lit for final and xor (their shared reference cached once).
set -u
start=$(date +%s)
source scripts/gpu-unpack.sh final
mkdir -p /tmp/xor /tmp/old && cp sobol/xor/sampler.wgsl /tmp/xor/ && cp sobol/old/sampler.wgsl /tmp/old/
ASSETS=rel/assets FRAMES=40 SCENES="cornell flight-helmet spheres" timeout 300 bash scripts/gpu-ab-frames.sh 2 final final:/tmp/xor final:/tmp/old
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
for v in final xor; do
  d=/nonexistent; [ $v = xor ] && d=/tmp/xor
  left=$(( 560 - ($(date +%s) - start) ))
  RAYKIN_SHADER_DIR=$d timeout "$left" rel/final bench --suite full --scene flight-helmet --scene env-lit --assets rel/assets \
    --parts errors --curve "16 spp" --out /tmp/err-$v --cache /tmp/err-cache > /tmp/err-$v.log 2>&1
  cp /tmp/err-$v/summary.md "$OUT/errors-$v.md"; cp /tmp/err-$v/curves.csv "$OUT/curves-$v.csv"
done
echo "total: $(( $(date +%s) - start )) s"
