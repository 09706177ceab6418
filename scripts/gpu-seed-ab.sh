#!/usr/bin/env bash
# The seed-like interior (2560x1440, 1 spp, depth 6, the bench's frame loop, 30 frames) per VARIANT
# `binary:integrator` (rel/BINARY, already unpacked: scripts/gpu-unpack.sh, or an earlier gpu-ab-frames.sh), alternating ROUNDS
# times within a budget of BUDGET seconds from START (epoch seconds; default now) so that a device call ends in
# time. Appends rows (variant, round, scene, width, height, trace ms median) to $OUT/seed.txt and prints them.
# Usage: bash scripts/gpu-seed-ab.sh ROUNDS VARIANT...
set -u
rounds=$1; shift
start=${START:-$(date +%s)} budget=${BUDGET:-570}
for round in $(seq "$rounds"); do
  for variant in "$@"; do
    left=$(( budget - ($(date +%s) - start) ))
    [ "$left" -lt 40 ] && break 2
    w=$(mktemp -d)
    timeout "$left" "rel/${variant%%:*}" bench --suite full --parts frames --frames 30 --scene seed-interior --width 2560 \
      --height 1440 --integrator "${variant#*:}" --assets "${ASSETS:-rel/assets}" --out "$w" --cache "$w/c" >> "$OUT/seed.log" 2>&1
    python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']: print('$variant', $round, row.get('scene'), row.get('width'), row.get('height'), row.get('trace_ms_median'))
" >> "$OUT/seed.txt"
    rm -rf "$w"
  done
done
cat "$OUT/seed.txt"
