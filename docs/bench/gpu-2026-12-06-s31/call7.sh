#!/usr/bin/env bash
# Thirty-first session, call 7, on the H200 of calls 5-6. relb/head.xz = 72fb682 run with RAYKIN_WAVE_REFILL=on
# RAYKIN_WAVE_REFILL_GROUPS=4096 (d6e55e1's default):
# 1. the Mitsuba 3 side by side of the seven static scenes (auto, three Mitsuba renders per count) -> summary.md,
#    traced-by.txt;
# 2. the seed-like interior and the crowd (2560x1440, 1 spp, depth 6, auto), two rounds -> seed.txt.
# Carry [".gl", "relb", ".whl"].
set -u
source scripts/gpu-unpack.sh
export RAYKIN_WAVE_REFILL=on RAYKIN_WAVE_REFILL_GROUPS=4096
MITSUBA_REPEATS=3 ASSETS=relb/assets RAYKIN_BIN=relb/head RAYKIN_INTEGRATOR=auto timeout 400 \
  bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
grep -h "traced by" /tmp/gpu-mitsuba/bench.log > "$OUT/traced-by.txt"
cp /tmp/gpu-mitsuba/mitsuba.log "$OUT/" 2>/dev/null
echo "side by side: $(elapsed) s" >> "$OUT/traced-by.txt"
for round in 1 2; do
  for scene in seed-interior crowd; do
    [ "$(elapsed)" -lt 440 ] && frame_rows head seed.txt relb/head RAYKIN_UNUSED=1 --scene $scene \
      --width 2560 --height 1440 --frames 24 --integrator auto
  done
done
echo "seed: $(elapsed) s" >> "$OUT/traced-by.txt"
cat "$OUT/gpu.txt" "$OUT/seed.txt"; grep -A10 "### Mitsuba" "$OUT/summary.md"; true
