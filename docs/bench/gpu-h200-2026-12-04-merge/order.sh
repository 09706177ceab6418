#!/usr/bin/env bash
# Device call: why many-lights traced 5% slower merged (ab-run1/2) while its shading-free rays got faster.
# Hypothesis: the members' instance records, and the light list built from them, came in node order, where the
# top level had given spatial (tree) order. raykin-n (3c97708: members in Morton order) against raykin-m
# (e80cc51: node order), both merged, and raykin-m with `--static-bvh wide`; three rounds, alternating, on
# many-lights, the Cornell box and FlightHelmet. Carry .gl and rel.
set -u
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
(cd rel && for b in raykin-m raykin-n; do xz -dkf $b.xz && chmod +x $b; done)
one() { # label binary layout round
  local w; w=$(mktemp -d)
  rel/$2 bench --suite full --parts frames --frames 60 --static-bvh "$3" --scene many-lights --scene cornell \
    --scene flight-helmet --assets rel/assets --out "$w" --cache "$w/c" >> "$OUT/bench.log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']: print('$1', $4, row.get('scene'), row.get('width'), row.get('height'), row.get('trace_ms_median'),
  row.get('raycast_camera_rays_per_s', 0) / 1e9, row.get('raycast_diffuse_rays_per_s', 0) / 1e9)
" >> "$OUT/ab.txt"
}
for round in 1 2 3; do
  one morton raykin-n merged $round; one node raykin-m merged $round; one wide raykin-m wide $round
done
awk '{k=$3" "$4"x"$5" "$1; s[k]+=$6; c[k]+=$7; d[k]+=$8; n[k]++}
  END {for (k in s) printf "%s trace_ms %.4f camera_G %.3f diffuse_G %.3f (n=%d)\n", k, s[k]/n[k], c[k]/n[k], d[k]/n[k], n[k]}' \
  "$OUT/ab.txt" | sort | tee "$OUT/summary.txt"
