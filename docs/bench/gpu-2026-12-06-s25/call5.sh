#!/usr/bin/env bash
# Twenty-fifth session, call 5 (the device time left: the spheres only). relb/head.xz = be9667a (call 3's binary);
# the Mitsuba plugin tests/reference/cornell/gltf_brdf.py with GGX D written without the cancellation that made it
# infinite at roughness 0 (the spheres' smooth column rendered dark in Mitsuba, with non-finite pixels). The
# Mitsuba 3 side by side of the spheres (`--integrator auto`, the median of three Mitsuba renders per count) ->
# summary.md, traced-by.txt.
# Made by `bash scripts/gpu-pack.sh --mitsuba`; carry [".gl", "relb", ".whl"].
set -u
source scripts/gpu-unpack.sh
MITSUBA_SCENES=spheres MITSUBA_REPEATS=3 ASSETS=relb/assets RAYKIN_BIN=relb/head RAYKIN_INTEGRATOR=auto \
  timeout "${CALL_UNTIL:-170}" bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
grep -h "traced by" /tmp/gpu-mitsuba/bench.log > "$OUT/traced-by.txt"
echo "side by side: $(elapsed) s" >> "$OUT/traced-by.txt"
grep -A4 "### Mitsuba" "$OUT/summary.md"
