#!/usr/bin/env bash
# Device call: env-lit's error vs trace time, the default against BRDF sampling only, each to 8192 spp (issue 15's >= 5x).
set -u
for f in .gl/*.deb; do dpkg -x $f / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
(cd rel && xz -dkf raykin.xz && chmod +x raykin)
export RAYKIN_COMMIT=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
w=$(mktemp -d)
rel/raykin bench --suite full --parts errors --scene env-lit --curve "BRDF sampling" --error-max-spp 8192 \
  --assets shared/assets --out "$w/b" --cache "$w/c" 2>&1 | tee "$OUT/envlit.log"
cp "$w/b/results.json" "$w/b/summary.md" "$w/b/curves.csv" "$OUT/"; cp "$w/b/charts/"*.png "$OUT/"
