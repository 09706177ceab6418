#!/usr/bin/env bash
# Twenty-fifth session, call 1. relb/head.xz = 0b270ad (Russian roulette from depth 4, shadow rays that move both
# ends off their surfaces). Parts:
# 1. the Mitsuba 3 side by side of the five static scenes (`--integrator auto`, the median of three Mitsuba renders
#    per count) -> summary.md, traced-by.txt; its raykin curves are the depth-4 run -> /tmp/rr/1-4;
# 2. the error part's curves with --rr-depth 7 (no roulette below the bench's depth 6) on all five scenes, and with
#    3 and 5 on the Cornell box (the bias fix changed its light) -> /tmp/rr/1-7, 1-3, 1-5;
# 3. rr-depth.py on both curves (the default and 16 spp a frame) -> rr.txt.
# Made by `bash scripts/gpu-pack.sh --mitsuba`; carry [".gl", "relb", ".whl"].
set -u
source scripts/gpu-unpack.sh
MITSUBA_REPEATS=3 ASSETS=relb/assets RAYKIN_BIN=relb/head RAYKIN_INTEGRATOR=auto timeout 330 \
  bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
grep -h "traced by" /tmp/gpu-mitsuba/bench.log | sed "s/^/depth 4: /" > "$OUT/traced-by.txt"
mkdir -p /tmp/rr/1-4
cp /tmp/gpu-mitsuba/bench/results.json /tmp/rr/1-4/
cp /tmp/gpu-mitsuba/mitsuba.log "$OUT/" 2>/dev/null
echo "side by side: $(elapsed) s" > "$OUT/rr.txt"
curves() { # DEPTH SCENES...
  local depth=$1; shift
  local args=(); for s in "$@"; do args+=(--scene "$s"); done
  relb/head bench --suite full "${args[@]}" --assets relb/assets --parts errors --curve "16 spp" --integrator auto \
    --rr-depth "$depth" --out "/tmp/rr/1-$depth" --cache /tmp/bench-cache > "/tmp/rr/1-$depth.log" 2>&1
  grep -h "traced by" "/tmp/rr/1-$depth.log" | sed "s/^/depth $depth: /" >> "$OUT/traced-by.txt"
  echo "depth $depth: $(elapsed) s" >> "$OUT/rr.txt"
}
curves 7 cornell spheres flight-helmet env-lit many-lights
curves 3 cornell
curves 5 cornell
for curve in default "16 spp"; do python3 docs/bench/gpu-2026-12-06-s25/rr-depth.py /tmp/rr "$curve" >> "$OUT/rr.txt"; done
cat "$OUT/rr.txt"; tail -9 "$OUT/summary.md"
