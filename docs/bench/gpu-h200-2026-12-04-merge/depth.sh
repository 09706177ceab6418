#!/usr/bin/env bash
# Device call: where FlightHelmet's trace time goes, by path depth (the binary of 64c8d5b, merged tree): the
# frame loop at --max-depth 0 (camera rays and what they see), 1, 2, 3 and 6, two rounds, FlightHelmet and the
# Cornell box (a closed room, for contrast). The increments are the cost of each further bounce (its ray, its
# shading, next-event estimation there). Carry .gl and rel.
set -u
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
(cd rel && xz -dkf raykin-h.xz && chmod +x raykin-h)
for round in 1 2; do
  for depth in 0 1 2 3 6; do
    w=$(mktemp -d)
    rel/raykin-h bench --suite full --parts frames --frames 40 --max-depth $depth --scene flight-helmet --scene cornell \
      --assets rel/assets --out "$w" --cache "$w/c" >> "$OUT/bench.log" 2>&1
    python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']: print($depth, $round, row.get('scene'), row.get('width'), row.get('height'), row.get('trace_ms_median'),
  row.get('all_rays_per_s', 0) / 1e9, row.get('rays_per_pixel_per_frame', 0))
" >> "$OUT/depth.txt"
  done
done
awk '{k=$3" "$4"x"$5" depth "$1; s[k]+=$6; r[k]+=$7; p[k]+=$8; n[k]++} END {for (k in s) printf "%s trace_ms %.4f rays_G %.3f rays_per_pixel %.3f\n", k, s[k]/n[k], r[k]/n[k], p[k]/n[k]}' \
  "$OUT/depth.txt" | sort | tee "$OUT/summary.txt"
