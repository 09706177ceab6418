#!/usr/bin/env bash
# Device call: environment-map sampling inside a cell, uniform (raykin-a, f141b89) against bilinear (raykin-b,
# 655ade0): the error-vs-time part of the sky- and map-lit static scenes with each binary (each renders its own
# reference: the kernel source is in the cache key), then the seed-like hall and the spheres through the frame
# loop at 2560x1440 with the new binary (trace time, shading-free camera and diffuse ray casting).
set -u
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
(cd rel && for b in raykin-a raykin-b; do xz -dkf $b.xz && chmod +x $b; done)
for b in raykin-a raykin-b; do
  RAYKIN_COMMIT=$b rel/$b bench --suite full --scene env-lit --scene flight-helmet --scene spheres --parts errors \
    --curve "16 spp" --assets shared/assets --out /tmp/ab-$b --cache /tmp/cache-$b > /tmp/ab-$b.log 2>&1
  echo "$b: rc $?"
  cp /tmp/ab-$b/summary.md "$OUT/errors-$b.md"
done
RAYKIN_COMMIT=655ade0 rel/raykin-b bench --suite full --scene seed-interior --scene spheres --parts frames \
  --width 2560 --height 1440 --assets shared/assets --out /tmp/seed > /tmp/seed.log 2>&1
echo "seed: rc $?"
cp /tmp/seed/summary.md "$OUT/frames-seed.md"
tail -n 40 /tmp/ab-raykin-b.log /tmp/seed.log > "$OUT/logs.txt"
