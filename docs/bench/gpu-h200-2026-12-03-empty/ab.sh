#!/usr/bin/env bash
# Device call: the traversals' per-node `index != NONE` check removed (EMPTY children are a box at +infinity that
# every slab test rejects) against the binary just before (raykin-a, daf0bbd): images first (same seed, EXR bytes
# compared; the Cornell box is a one-instance top-level tree, so every ray meets EMPTY), then trace time, the two
# dev-profile binaries alternating three times.
set -u
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
(cd rel && for b in raykin-a raykin-b; do xz -dkf $b.xz && chmod +x $b; done)
for scene in CornellBox/CornellBox.glb FlightHelmet/glTF/FlightHelmet.gltf CesiumMan/glTF-Binary/CesiumMan.glb; do
  name=$(basename "$scene" | cut -d. -f1)
  for b in raykin-a raykin-b; do
    rel/$b render "shared/assets/$scene" --spp 64 --width 512 --height 512 --seed 7 --out "/tmp/$name-$b.exr" \
      >> "$OUT/render.log" 2>&1
  done
  if cmp -s "/tmp/$name-raykin-a.exr" "/tmp/$name-raykin-b.exr"; then echo "$name: identical"; else echo "$name: DIFFERENT"; fi
done | tee "$OUT/images.txt"
exec bash scripts/gpu-ab-frames.sh 3 raykin-a raykin-b
