#!/usr/bin/env bash
# Twenty-seventh session, call 2: where the sort's time goes. `RAYKIN_WAVE_PROFILE=on` (each stage of the first
# wave its own timed pass: extend alone, then shade + advance + the sort), the seed-like interior and the Cornell
# box in waves, sort off and on -> profile.txt (the bench log's profile lines).
set -u
source scripts/gpu-unpack.sh
prof() {
  local w; w=$(mktemp -d); local sort=$1 scene=$2; shift 2
  RAYKIN_WAVE_PROFILE=on RAYKIN_WAVE_SORT=$sort RUST_LOG=info relb/head bench --suite full --parts frames --scene "$scene" "$@" \
    --frames 12 --assets relb/assets --out "$w" --cache "$w/c" > "$w/log" 2>&1
  echo "sort-$sort $scene" >> "$OUT/profile.txt"
  grep "wavefront profile" "$w/log" | tail -2 >> "$OUT/profile.txt" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
for sort in off on; do
  prof $sort seed-interior --width 2560 --height 1440 --integrator wavefront
  prof $sort cornell --width 960 --height 540 --spp-per-frame 16 --integrator wavefront
done
cat "$OUT/profile.txt"; cat "$OUT/errors.txt" 2>/dev/null
