#!/usr/bin/env bash
# Device call 3: the megakernel, the wavefront integrator with its first bounce as a megakernel (first_bounce),
# and the same with 64-thread queue workgroups (rel/wg64/wavefront.wgsl); same binary, same call,
# alternating (two rounds), then the seed-like interior.
set -u
start=$(date +%s)
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv > "$OUT/gpu.txt"
ASSETS=rel/assets FRAMES=40 SCENES="cornell flight-helmet spheres env-lit crowd" timeout 400 \
  bash scripts/gpu-ab-frames.sh 2 head head,--integrator=wavefront head:rel/wg64,--integrator=wavefront > "$OUT/ab-summary.txt"
cat "$OUT/ab-summary.txt"
echo "static scenes: $(( $(date +%s) - start )) s"
for round in 1 2; do
  for variant in megakernel wavefront wg64; do
    left=$(( 570 - ($(date +%s) - start) ))
    [ "$left" -lt 40 ] && break 2
    w=$(mktemp -d)
    integrator=$variant; dir=/nonexistent
    [ "$variant" = wg64 ] && { integrator=wavefront; dir=rel/wg64; }
    RAYKIN_SHADER_DIR=$dir timeout "$left" rel/head bench --suite full --parts frames --frames 30 --scene seed-interior --width 2560 \
      --height 1440 --integrator "$integrator" --assets rel/assets --out "$w" --cache "$w/c" >> "$OUT/seed.log" 2>&1
    python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']: print('$variant', $round, row.get('scene'), row.get('width'), row.get('height'), row.get('trace_ms_median'))
" >> "$OUT/seed.txt"
  done
done
cat "$OUT/seed.txt"
echo "total: $(( $(date +%s) - start )) s"
