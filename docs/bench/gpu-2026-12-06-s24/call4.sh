#!/usr/bin/env bash
# Twenty-fourth session, call 4 (the device time left: the Cornell box only). relb/head.xz = Russian roulette
# from depth 4 and shadow rays that move both ends off their surfaces (traversal/ray.wgsl `spawn_ray_to`: next-event
# estimation was blocked in the slit above the lamp, the box 0.989x Mitsuba's brightness). The Mitsuba 3 side by
# side of the Cornell box (`--integrator auto`, the median of three Mitsuba renders per count) -> summary.md.
# Made by `bash scripts/gpu-pack.sh --mitsuba`; carry [".gl", "relb", ".whl"].
set -u
source scripts/gpu-unpack.sh
MITSUBA_SCENES=cornell MITSUBA_REPEATS=3 ASSETS=relb/assets RAYKIN_BIN=relb/head RAYKIN_INTEGRATOR=auto \
  timeout "${CALL_UNTIL:-200}" bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
grep -h "traced by" /tmp/gpu-mitsuba/bench.log > "$OUT/traced-by.txt"
echo "side by side: $(elapsed) s" >> "$OUT/traced-by.txt"
tail -5 "$OUT/summary.md"
