#!/usr/bin/env bash
# One device call: the frames part of the bench (frame loop, shading-free ray casting and, new, the traversal work
# per ray) on the H200, at 1920x1080 and 2560x1440. Binaries (tree at opt-level 3, stripped): rel/raykin-t.xz =
# fda45ef (counting run, TRAVERSAL_STATS in every traversal, folded away outside the counting pipeline) and
# rel/raykin-o.xz = 60b1e1f (before it), run alternately per scene so that the trace times are a same-call A/B
# of the counting support's cost (expected: none). rel/assets: CornellBox, FlightHelmet, MetalRoughSpheresNoTextures,
# CesiumMan, Fox.
set -u
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
(cd rel && for b in raykin-t raykin-o; do xz -dkf $b.xz && chmod +x $b; done)
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
w=$(mktemp -d)
run() { # binary scene round
  timeout 150 rel/$1 bench --suite full --parts frames --scene "$2" --assets rel/assets --out "$w/$1-$2-$3" \
    --cache "$w/c" > "$w/$1-$2-$3.log" 2>&1
  echo "$1 $2 round $3 rc $?"; grep -h "raykin bench: $2 " "$w/$1-$2-$3.log" | grep -v "deform backend" | cut -c1-400
}
for s in spheres flight-helmet cornell env-lit; do run raykin-t "$s" 1; run raykin-o "$s" 1; done
for s in spheres flight-helmet cornell; do run raykin-o "$s" 2; run raykin-t "$s" 2; done
run raykin-t seed-interior 1
mkdir -p "$w/out"
for d in "$w"/raykin-*; do [ -d "$d" ] && cp "$d/results.json" "$w/out/$(basename "$d").json" 2>/dev/null; done
(cd "$w/out" && tar -cf "$OUT/results.tar" .)
