#!/usr/bin/env bash
# Twenty-ninth session, call 5: the Cornell box's side by side on an H200, if one came (the target names the
# H200; every call of the last sessions got an H100): on any other card it stops at once. relb/head.xz = the
# session's head. Then the seed-like interior and the crowd under auto. Carry [".gl", "relb", ".whl"].
set -u
source scripts/gpu-unpack.sh
if ! grep -q H200 "$OUT/gpu.txt"; then echo "not an H200: stopped" >> "$OUT/gpu.txt"; cat "$OUT/gpu.txt"; exit 0; fi
MITSUBA_SCENES=cornell MITSUBA_REPEATS=3 ASSETS=relb/assets RAYKIN_BIN=relb/head RAYKIN_INTEGRATOR=auto \
  timeout 300 bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
cp /tmp/gpu-mitsuba/mitsuba.log "$OUT/" 2>/dev/null
for scene in seed-interior crowd; do
  [ "$(elapsed)" -lt 400 ] && frame_rows head seed.txt relb/head RAYKIN_UNUSED=1 --scene $scene \
    --width 2560 --height 1440 --frames 24 --integrator auto
done
cat "$OUT/gpu.txt" "$OUT/seed.txt"; grep -A4 "### Mitsuba" "$OUT/summary.md"
