#!/usr/bin/env bash
# Device call 2: trace time per frame, same call, alternating: base = dbf2fc4 (the thirteenth session's start),
# head = 68fb315, head + the Owen-scrambled Sobol' sampler (sobol/sampler.wgsl).
set -u
start=$(date +%s)
cp sobol/sampler.wgsl /tmp/sampler.wgsl 2>/dev/null; mkdir -p /tmp/sobdir && cp sobol/sampler.wgsl /tmp/sobdir/
ASSETS=rel/assets FRAMES=40 timeout 540 bash scripts/gpu-ab-frames.sh 2 base head head:/tmp/sobdir
echo "total: $(( $(date +%s) - start )) s"
