#!/usr/bin/env bash
# Device call: the clearcoat/sheen/unlit branch (raykin-c, h/coat 9e4702e) against its base (raykin-a, daf0bbd):
# scenes without the layers must render the same bytes and trace as fast (the material record grew from 112 to
# 160 B); then the layered ClearCoatTest rendered with the branch (finite, its time). Trace time: the bench frame
# loop, the two dev-profile binaries alternating three times.
set -u
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
(cd rel && for b in raykin-a raykin-c; do xz -dkf $b.xz && chmod +x $b; done)
for scene in CornellBox/CornellBox.glb FlightHelmet/glTF/FlightHelmet.gltf CesiumMan/glTF-Binary/CesiumMan.glb; do
  name=$(basename "$scene" | cut -d. -f1)
  for b in raykin-a raykin-c; do
    rel/$b render "shared/assets/$scene" --spp 64 --width 512 --height 512 --seed 7 --out "/tmp/$name-$b.exr" \
      >> "$OUT/render.log" 2>&1
  done
  if cmp -s "/tmp/$name-raykin-a.exr" "/tmp/$name-raykin-c.exr"; then echo "$name: identical"; else echo "$name: DIFFERENT"; fi
done | tee "$OUT/images.txt"
for b in raykin-a raykin-c; do
  s=$(date +%s%N)
  rel/$b render shared/assets/ClearCoatTest/glTF-Binary/ClearCoatTest.glb --spp 256 --width 1024 --height 768 \
    --seed 7 --out "$OUT/clearcoat-$b.png" >> "$OUT/render.log" 2>&1
  echo "ClearCoatTest $b: rc $? $(( ($(date +%s%N) - s) / 1000000 )) ms" | tee -a "$OUT/images.txt"
done
exec bash scripts/gpu-ab-frames.sh 3 raykin-a raykin-c
