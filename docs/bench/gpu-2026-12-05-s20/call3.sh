#!/usr/bin/env bash
# Twentieth session, call 3 (relb/head.xz = 07cae21's stripped release build: the merged static tree built
# with VerySlow and its spatial splits), the Mitsuba 3 side by side (scripts/gpu-mitsuba.sh) on all five static scenes with the
# default `--integrator auto`, one Mitsuba render per count; then the frame loop with auto at 960x540, 16 spp per
# frame (its trials' times and choices) and the seed-like interior at 2560x1440, 1 spp -> frames.txt. Carry
# [".gl", "relb", ".whl"]; relb/assets holds CornellBox, FlightHelmet, MetalRoughSpheresNoTextures, CesiumMan,
# Fox; .whl Dr.Jit 1.5.0's cp312 wheel and `KEEP_DATA= bash scripts/strip-mitsuba-wheel.sh mitsuba-3.9.1-*.whl
# .whl/mitsuba-strip.tar.xz`. Calls 4, 5 and 7 run this script with: MITSUBA_REPEATS (Mitsuba renders per count,
# default 1), SIDE_BY_SIDE_SECONDS (the side by side's limit, default 420), FRAMES=off (no frame loop).
set -u
source scripts/gpu-unpack.sh
export RAYKIN_COMMIT=07cae21
MITSUBA_REPEATS=${MITSUBA_REPEATS:-1} ASSETS=relb/assets RAYKIN_BIN=relb/head RAYKIN_INTEGRATOR=auto \
  timeout "${SIDE_BY_SIDE_SECONDS:-420}" bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
echo "side by side: $(elapsed) s"
grep -v warning /tmp/run.log | tail -n 30 > "$OUT/run-tail.log"
grep -h "traced by" /tmp/gpu-mitsuba/bench.log > "$OUT/traced-by.txt"
frames() {  # bench options...
  local w; w=$(mktemp -d)
  relb/head bench --suite full --parts frames --frames 30 "$@" --assets relb/assets --out "$w" --cache "$w/c" \
    >> /tmp/frames.log 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']: print(row['scene'], row['width'], row['spp_per_frame'], row['trace_ms_median'], row['integrator'], row.get('auto_trial_ms'))
" >> "$OUT/frames.txt"
}
[ "${FRAMES:-on}" = on ] && [ "$(elapsed)" -lt 500 ] && frames --scene cornell --scene flight-helmet --scene spheres --scene env-lit --width 960 --height 540 --spp-per-frame 16
[ "${FRAMES:-on}" = on ] && [ "$(elapsed)" -lt 540 ] && frames --scene seed-interior --width 2560 --height 1440
echo "total: $(elapsed) s" | tee -a "$OUT/frames.txt"
cat "$OUT/frames.txt" "$OUT/traced-by.txt"
grep -A12 "time to equal error" "$OUT/summary.md" | head -20
