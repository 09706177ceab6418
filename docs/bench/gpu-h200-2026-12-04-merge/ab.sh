#!/usr/bin/env bash
# Device call: static instances merged into one wide BVH (`--static-bvh merged`, the new default) against one
# wide BVH per mesh under the top level (`--static-bvh wide`, the layout before), same binary (rel/raykin-m.xz),
# the bench's frame loop on every named scene, the two alternating ROUNDS times (trace kernel median of 60
# frames per size, shading-free camera and diffuse ray rates). Carry .gl and rel (rel/assets: CornellBox,
# FlightHelmet, MetalRoughSpheresNoTextures, CesiumMan, Fox).
set -u
rounds=${1:-3}
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
(cd rel && xz -dkf raykin-m.xz && chmod +x raykin-m)
scenes=(--scene cornell --scene flight-helmet --scene spheres --scene env-lit --scene many-lights --scene crowd)
one() { # variant round scene-args...
  local v=$1 round=$2; shift 2
  local w; w=$(mktemp -d)
  rel/raykin-m bench --suite full --parts frames --frames 60 --static-bvh "$v" "$@" --assets rel/assets \
    --out "$w" --cache "$w/c" >> "$OUT/bench.log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']: print('$v', $round, row.get('scene'), row.get('width'), row.get('height'), row.get('trace_ms_median'),
  row.get('raycast_camera_rays_per_s', 0) / 1e9, row.get('raycast_diffuse_rays_per_s', 0) / 1e9)
" >> "$OUT/ab.txt"
}
for round in $(seq "$rounds"); do
  one merged "$round" "${scenes[@]}"; one wide "$round" "${scenes[@]}"
done
for round in 1 2; do
  one wide "$round" --scene seed-interior; one merged "$round" --scene seed-interior
done
awk '{k=$3" "$4"x"$5" "$1; s[k]+=$6; c[k]+=$7; d[k]+=$8; n[k]++}
  END {for (k in s) printf "%s trace_ms %.4f camera_G %.3f diffuse_G %.3f (n=%d)\n", k, s[k]/n[k], c[k]/n[k], d[k]/n[k], n[k]}' \
  "$OUT/ab.txt" | sort | tee "$OUT/summary.txt"
grep -h "static\|merge" "$OUT/bench.log" | sort | uniq -c | head
