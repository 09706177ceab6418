#!/usr/bin/env bash
# Twenty-seventh session, call 3: the sort's second form, extend alone reading the queue in the keys' order
# (a sorted copy) and shade the queue's own order. Profile lines of the seed-like interior and the Cornell box
# (call 2's), then call 1's frame rows for the scenes auto traces in waves (the seed, env-lit, many-lights) and the
# crowd, sort off and on alternating, two rounds -> profile.txt, sort.txt.
set -u
source scripts/gpu-unpack.sh
prof() {
  local w; w=$(mktemp -d); local sort=$1 scene=$2; shift 2
  RAYKIN_WAVE_PROFILE=on RAYKIN_WAVE_SORT=$sort RUST_LOG=info relb/head bench --suite full --parts frames --scene "$scene" "$@" \
    --frames 12 --assets relb/assets --out "$w" --cache "$w/c" > "$w/log" 2>&1
  echo "sort-$sort $scene" >> "$OUT/profile.txt"
  grep "wavefront profile" "$w/log" | tail -1 >> "$OUT/profile.txt" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
rows() {
  local w; w=$(mktemp -d); local label=$1 sort=$2 scene=$3; shift 3
  RAYKIN_WAVE_SORT=$sort relb/head bench --suite full --parts frames --scene "$scene" "$@" \
    --frames 24 --assets relb/assets --out "$w" --cache "$w/c" > "$w/log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']:
    print('$label', row['scene'], row['width'], round(row['trace_ms_median'],3), round(row['frame_ms']['median'],3), row['integrator'])
" >> "$OUT/sort.txt" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
for sort in off on; do
  prof $sort seed-interior --width 2560 --height 1440 --integrator wavefront
  prof $sort cornell --width 960 --height 540 --spp-per-frame 16 --integrator wavefront
done
for round in 1 2; do
  for sort in off on; do
    rows sort-$sort $sort seed-interior --width 2560 --height 1440 --integrator wavefront
    rows sort-$sort $sort crowd --width 2560 --height 1440 --integrator wavefront
    for scene in env-lit many-lights cornell; do
      rows sort-$sort $sort $scene --width 960 --height 540 --spp-per-frame 16 --integrator wavefront
    done
  done
done
cat "$OUT/gpu.txt" "$OUT/profile.txt" "$OUT/sort.txt"; cat "$OUT/errors.txt" 2>/dev/null
