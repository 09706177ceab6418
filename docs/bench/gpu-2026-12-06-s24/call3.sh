#!/usr/bin/env bash
# Twenty-fourth session, call 3. relb/head.xz = Russian roulette from depth 4 by default (call 2's default curve
# chose it). Parts:
# 1. rr3: the error part's curves of the five static scenes (960x540, depth 6, `--integrator auto`) with
#    --rr-depth 3, the same-call baseline -> /tmp/rr/1-3;
# 2. the Mitsuba 3 side by side with the default (depth 4), whose raykin curves are the depth-4 run -> /tmp/rr/1-4,
#    summary.md, traced-by.txt;
# 3. rr-depth.py on both curves (the default and 16 spp a frame) -> rr.txt.
# Made by `bash scripts/gpu-pack.sh --mitsuba`; carry [".gl", "relb", ".whl"].
set -u
source scripts/gpu-unpack.sh
scenes=(--scene cornell --scene spheres --scene flight-helmet --scene env-lit --scene many-lights)
mkdir -p /tmp/rr/1-4
relb/head bench --suite full "${scenes[@]}" --assets relb/assets --parts errors --curve "16 spp" --integrator auto \
  --rr-depth 3 --out /tmp/rr/1-3 --cache /tmp/bench-cache > /tmp/rr/1-3.log 2>&1
grep -h "traced by" /tmp/rr/1-3.log | sed "s/^/depth 3: /" > "$OUT/traced-by.txt"
echo "depth 3: $(elapsed) s" > "$OUT/rr.txt"
MITSUBA_REPEATS=3 ASSETS=relb/assets RAYKIN_BIN=relb/head RAYKIN_INTEGRATOR=auto timeout $(( 570 - $(elapsed) )) \
  bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
grep -h "traced by" /tmp/gpu-mitsuba/bench.log | sed "s/^/depth 4: /" >> "$OUT/traced-by.txt"
cp /tmp/gpu-mitsuba/bench/results.json /tmp/rr/1-4/
cp /tmp/gpu-mitsuba/mitsuba.log "$OUT/" 2>/dev/null
echo "side by side: $(elapsed) s" >> "$OUT/rr.txt"
for curve in default "16 spp"; do python3 docs/bench/gpu-2026-12-06-s24/rr-depth.py /tmp/rr "$curve" >> "$OUT/rr.txt"; done
cat "$OUT/rr.txt"; tail -9 "$OUT/summary.md"
