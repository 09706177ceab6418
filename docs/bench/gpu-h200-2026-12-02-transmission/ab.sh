#!/usr/bin/env bash
# Device call: trace time before (a1d0057) and after (extension lobes with kernels specialised per scene:
# MATERIAL_LOBES pipeline constant), alternating twice; then AttenuationTest (Factors kernel) rendered by both.
set -u
bash scripts/gpu-ab-frames.sh 2 raykin-old raykin-spec
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
for b in raykin-old raykin-spec; do
  rel/$b render shared/assets/AttenuationTest/glTF/AttenuationTest.gltf --spp 1024 --width 1280 --height 720 --max-depth 12 \
    --look-from 0.5,0,17 --look-at 0.5,0,0 --fov 45 --out "$OUT/attenuation-$b.png" >> "$OUT/render.log" 2>&1
done
grep wrote "$OUT/render.log"
