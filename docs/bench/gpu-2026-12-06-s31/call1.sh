#!/usr/bin/env bash
# Thirty-first session, call 1. relb/head.xz = 72fb682: the waves' extend with refill (RAYKIN_WAVE_REFILL=on|off),
# now with alpha-blend pass-throughs (faef3f2), so the seed-like interior refills too.
# 1. On an H200 only: the Cornell box's side by side (the time-to-equal-error target's card).
# 2. refill.txt (label, scene, width, trace ms median, frame ms median, form, rays sorted): the seed-like interior
#    and the crowd at 2560x1440, 1 spp, depth 6, two rounds: waves forced and sorted, refill off / 2048 / 4096
#    groups; auto with refill off / on.
# 3. static.txt (frame_rows): cornell, env-lit, many-lights, spheres, flight-helmet at 960x540, 16 spp a frame,
#    waves forced with refill off / on, and auto with refill off / on.
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
  local w; w=$(mktemp -d); local label=$1 envs=$2 scene=$3; shift 3
  [ "$(elapsed)" -lt 500 ] || return
  env $envs timeout 80 relb/head bench --suite full --parts frames --scene "$scene" "$@" \
    --frames 24 --assets relb/assets --out "$w" --cache "$w/c" > "$w/log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']:
    print('$label', row['scene'], row['width'], round(row['trace_ms_median'],3), round(row['frame_ms']['median'],3), row['integrator'], row.get('rays_sorted'))
" >> "$OUT/refill.txt" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
big="--width 2560 --height 1440"
for round in 1 2; do
  for scene in seed-interior crowd; do
    rows waves-off "RAYKIN_WAVE_SORT=on RAYKIN_WAVE_REFILL=off" $scene $big --integrator wavefront
    rows waves-2048 "RAYKIN_WAVE_SORT=on RAYKIN_WAVE_REFILL=on RAYKIN_WAVE_REFILL_GROUPS=2048" $scene $big --integrator wavefront
    rows waves-4096 "RAYKIN_WAVE_SORT=on RAYKIN_WAVE_REFILL=on RAYKIN_WAVE_REFILL_GROUPS=4096" $scene $big --integrator wavefront
    rows auto-off "RAYKIN_WAVE_REFILL=off" $scene $big --integrator auto
    rows auto-on "RAYKIN_WAVE_REFILL=on" $scene $big --integrator auto
  done
done
echo "refill: $(elapsed) s" >> "$OUT/refill.txt"
statics=(--scene cornell --scene env-lit --scene many-lights --scene spheres --scene flight-helmet)
for round in 1 2; do
  for form in wavefront auto; do
    for refill in off on; do
      [ "$(elapsed)" -lt 540 ] || break
      frame_rows "$form-$refill" static.txt relb/head RAYKIN_WAVE_REFILL=$refill "${statics[@]}" \
        --width 960 --height 540 --spp-per-frame 16 --frames 24 --integrator $form
    done
  done
done
echo "static: $(elapsed) s" >> "$OUT/static.txt"
cat "$OUT/gpu.txt" "$OUT/refill.txt" "$OUT/static.txt"; cat "$OUT/errors.txt" 2>/dev/null
grep -A4 "### Mitsuba" "$OUT/summary.md" 2>/dev/null; true
