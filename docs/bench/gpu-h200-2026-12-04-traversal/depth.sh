#!/usr/bin/env bash
# Second call of the traversal study: the path kernel's cost per sample against its depth. `raykin bench --suite
# full --parts frames --width 2560 --height 1440 --max-depth D` for D = 0 (the camera ray, its shading and
# next-event estimation at the first hit), 1, 2 and 6, per scene, binary rel/raykin-t.xz (fda45ef at opt-level 3).
set -u
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
(cd rel && xz -dkf raykin-t.xz && chmod +x raykin-t)
w=$(mktemp -d); mkdir -p "$w/out"
for s in flight-helmet cornell spheres env-lit; do
  for d in 0 1 2 6; do
    timeout 90 rel/raykin-t bench --suite full --parts frames --scene "$s" --max-depth "$d" --width 2560 \
      --height 1440 --assets rel/assets --out "$w/$s-$d" --cache "$w/c" > "$w/$s-$d.log" 2>&1
    echo "$s depth $d rc $?: $(grep -h "raykin bench: $s 2560x1440: [0-9.]* ms/frame" "$w/$s-$d.log" | cut -c1-240)"
    cp "$w/$s-$d/results.json" "$w/out/$s-depth$d.json" 2>/dev/null
  done
done
(cd "$w/out" && tar -cf "$OUT/depth.tar" .)
