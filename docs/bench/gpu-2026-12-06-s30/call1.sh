#!/usr/bin/env bash
# Thirtieth session, call 1. relb/head.xz = 0d7310a: the waves' extend with refill (RAYKIN_WAVE_REFILL=on,
# RAYKIN_WAVE_REFILL_GROUPS=N workgroups at most; off: one ray an invocation, the default).
# (Ran on an H100, so part 1 was skipped. This binary refilled only scenes without alpha-blended materials, a gate
# faef3f2 removed: the seed-like interior, whose FlightHelmets blend, never refilled, hence its equal rows.)
# 1. On an H200 only (the target's card; none came in the last six sessions): the Cornell box's side by side.
# 2. The seed-like interior and the crowd at 2560x1440, 1 spp, depth 6, waves forced, two rounds: sorted with
#    refill off and at 512, 1024, 2048, 4096 groups; unsorted off and 1024 -> refill.txt: label, scene, width,
#    trace ms median, frame ms median, form, rays sorted.
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
  [ "$(elapsed)" -lt 540 ] || return
  env $envs timeout 80 relb/head bench --suite full --parts frames --scene "$scene" "$@" \
    --frames 24 --assets relb/assets --out "$w" --cache "$w/c" > "$w/log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']:
    print('$label', row['scene'], row['width'], round(row['trace_ms_median'],3), round(row['frame_ms']['median'],3), row['integrator'], row.get('rays_sorted'))
" >> "$OUT/refill.txt" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
big="--width 2560 --height 1440 --integrator wavefront"
for round in 1 2; do
  rows sorted-off "RAYKIN_WAVE_SORT=on RAYKIN_WAVE_REFILL=off" seed-interior $big
  for g in 512 1024 2048 4096; do
    rows sorted-$g "RAYKIN_WAVE_SORT=on RAYKIN_WAVE_REFILL=on RAYKIN_WAVE_REFILL_GROUPS=$g" seed-interior $big
  done
  rows unsorted-off "RAYKIN_WAVE_SORT=off RAYKIN_WAVE_REFILL=off" seed-interior $big
  rows unsorted-1024 "RAYKIN_WAVE_SORT=off RAYKIN_WAVE_REFILL=on RAYKIN_WAVE_REFILL_GROUPS=1024" seed-interior $big
  rows sorted-off "RAYKIN_WAVE_SORT=on RAYKIN_WAVE_REFILL=off" crowd $big
  rows sorted-1024 "RAYKIN_WAVE_SORT=on RAYKIN_WAVE_REFILL=on RAYKIN_WAVE_REFILL_GROUPS=1024" crowd $big
  rows sorted-2048 "RAYKIN_WAVE_SORT=on RAYKIN_WAVE_REFILL=on RAYKIN_WAVE_REFILL_GROUPS=2048" crowd $big
done
echo "refill: $(elapsed) s" >> "$OUT/refill.txt"
cat "$OUT/gpu.txt" "$OUT/refill.txt"; cat "$OUT/errors.txt" 2>/dev/null
grep -A4 "### Mitsuba" "$OUT/summary.md" 2>/dev/null; true
