#!/usr/bin/env bash
# Thirty-first session, call 3. relb/head.xz = 72fb682 again: the default to be, refill at 4096 workgroups, under
# auto (its trials choose the form and the sort) against refill off.
# 1. On an H200 only: the Cornell box's side by side.
# 2. auto.txt: every bench static scene at 960x540, 16 spp a frame, and the seed-like interior and the crowd at
#    2560x1440, 1 spp, under auto, refill off / on at 4096 groups, two rounds.
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
FILE=auto.txt
statics=(--scene cornell --scene env-lit --scene many-lights --scene spheres --scene flight-helmet --scene furnace --scene grazing)
for round in 1 2; do
  for refill in off on; do
    envs="RAYKIN_WAVE_REFILL=$refill RAYKIN_WAVE_REFILL_GROUPS=4096"
    rows $refill "$envs" "${statics[@]}" --width 960 --height 540 --spp-per-frame 16 --integrator auto
    rows $refill "$envs" --scene seed-interior --scene crowd --width 2560 --height 1440 --integrator auto
  done
done
echo "auto: $(elapsed) s" >> "$OUT/auto.txt"
cat "$OUT/gpu.txt" "$OUT/auto.txt"; cat "$OUT/errors.txt" 2>/dev/null
grep -A4 "### Mitsuba" "$OUT/summary.md" 2>/dev/null; true
