#!/usr/bin/env bash
# Thirty-first session, call 2. relb/head.xz = 72fb682 again: the refill grid's size. Call 1 found 4096
# workgroups faster than 2048 on the seed-like interior and the crowd; larger grids here.
# 1. On an H200 only: the Cornell box's side by side.
# 2. refill.txt: the seed-like interior and the crowd at 2560x1440, 1 spp, depth 6, waves forced and sorted, refill
#    off / 4096 / 8192 / 16384 / 32768 groups, two rounds.
# 3. static.txt (frame_rows): cornell, env-lit, many-lights, spheres, flight-helmet at 960x540, 16 spp a frame,
#    waves forced unsorted (as auto's first trial times them), refill off / 4096 / 8192 / 16384, two rounds.
# Carry [".gl", "relb", ".whl"].
set -u
source scripts/gpu-unpack.sh
if grep -q H200 "$OUT/gpu.txt"; then
  MITSUBA_SCENES=cornell MITSUBA_REPEATS=3 ASSETS=relb/assets RAYKIN_BIN=relb/head RAYKIN_INTEGRATOR=auto \
    timeout 200 bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
  cp /tmp/gpu-mitsuba/mitsuba.log "$OUT/" 2>/dev/null
  echo "side by side: $(elapsed) s" >> "$OUT/gpu.txt"
fi
rows() {
  local w; w=$(mktemp -d); local label=$1 envs=$2; shift 2
  [ "$(elapsed)" -lt 500 ] || return
  env $envs timeout 80 relb/head bench --suite full --parts frames "$@" \
    --frames 24 --assets relb/assets --out "$w" --cache "$w/c" > "$w/log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']:
    print('$label', row['scene'], row['width'], row['spp_per_frame'], round(row['trace_ms_median'],3), round(row['frame_ms']['median'],3), row['integrator'], row.get('rays_sorted'))
" >> "$OUT/$FILE" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
FILE=refill.txt
for round in 1 2; do
  for scene in seed-interior crowd; do
    rows off "RAYKIN_WAVE_SORT=on RAYKIN_WAVE_REFILL=off" --scene $scene --width 2560 --height 1440 --integrator wavefront
    for g in 4096 8192 16384 32768; do
      rows $g "RAYKIN_WAVE_SORT=on RAYKIN_WAVE_REFILL=on RAYKIN_WAVE_REFILL_GROUPS=$g" --scene $scene --width 2560 --height 1440 --integrator wavefront
    done
  done
done
echo "refill: $(elapsed) s" >> "$OUT/refill.txt"
FILE=static.txt
statics=(--scene cornell --scene env-lit --scene many-lights --scene spheres --scene flight-helmet)
for round in 1 2; do
  rows off "RAYKIN_WAVE_SORT=off RAYKIN_WAVE_REFILL=off" "${statics[@]}" --width 960 --height 540 --spp-per-frame 16 --integrator wavefront
  for g in 4096 8192 16384; do
    rows $g "RAYKIN_WAVE_SORT=off RAYKIN_WAVE_REFILL=on RAYKIN_WAVE_REFILL_GROUPS=$g" "${statics[@]}" --width 960 --height 540 --spp-per-frame 16 --integrator wavefront
  done
done
echo "static: $(elapsed) s" >> "$OUT/static.txt"
cat "$OUT/gpu.txt" "$OUT/refill.txt" "$OUT/static.txt"; cat "$OUT/errors.txt" 2>/dev/null
grep -A4 "### Mitsuba" "$OUT/summary.md" 2>/dev/null; true
