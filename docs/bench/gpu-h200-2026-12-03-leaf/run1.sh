#!/usr/bin/env bash
# Device call: static meshes' triangles gathered in BVH leaf order (raykin-b: one 48-byte fetch per triangle
# test) against the binary just before (raykin-a, 45cb732: the vertex indices, then three vertex fetches).
# Images first (same seed, EXR bytes compared), then trace time and ray-casting rates, the two dev-profile
# binaries alternating three times on the four bench scenes, then twice on the seed-like interior.
set -u
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
(cd rel && for b in raykin-a raykin-b; do xz -dkf $b.xz && chmod +x $b; done)
for scene in CornellBox/CornellBox.glb FlightHelmet/glTF/FlightHelmet.gltf CesiumMan/glTF-Binary/CesiumMan.glb \
    MetalRoughSpheresNoTextures/glTF-Binary/MetalRoughSpheresNoTextures.glb; do
  name=$(basename "$scene" | cut -d. -f1)
  for b in raykin-a raykin-b; do
    rel/$b render "shared/assets/$scene" --spp 64 --width 512 --height 512 --seed 7 --out "/tmp/$name-$b.exr" \
      >> "$OUT/render.log" 2>&1
  done
  if cmp -s "/tmp/$name-raykin-a.exr" "/tmp/$name-raykin-b.exr"; then echo "$name: identical"; else echo "$name: DIFFERENT"; fi
done | tee "$OUT/images.txt"
bash scripts/gpu-ab-frames.sh 3 raykin-a raykin-b
mkdir -p "$OUT/seed"
OUT="$OUT/seed" SCENES=seed-interior bash scripts/gpu-ab-frames.sh 2 raykin-a raykin-b
