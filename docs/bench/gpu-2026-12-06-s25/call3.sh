#!/usr/bin/env bash
# Twenty-fifth session, call 3. relb/head.xz = be9667a (the side by side's time at equal error, the furnace and
# grazing scenes, spherical-triangle sampling without asin); relb/old-shaders = 0b270ad's kernels. Parts:
# 1. the Mitsuba 3 side by side of the seven static scenes (`--integrator auto`, the median of three Mitsuba renders
#    per count) -> summary.md, traced-by.txt;
# 2. the seed-like interior (2560x1440, 1 spp, depth 6, its six ceiling panels sampled by solid angle), old and new
#    kernels alternating, two rounds -> seed.txt.
# Made by `bash scripts/gpu-pack.sh --mitsuba` and `git archive 0b270ad shaders | tar -x -C relb/old-shaders`;
# carry [".gl", "relb", ".whl"].
set -u
source scripts/gpu-unpack.sh
MITSUBA_REPEATS=3 ASSETS=relb/assets RAYKIN_BIN=relb/head RAYKIN_INTEGRATOR=auto timeout 400 \
  bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
grep -h "traced by" /tmp/gpu-mitsuba/bench.log > "$OUT/traced-by.txt"
cp /tmp/gpu-mitsuba/mitsuba.log "$OUT/" 2>/dev/null
echo "side by side: $(elapsed) s" >> "$OUT/traced-by.txt"
for round in 1 2; do
  for variant in old new; do
    if [ $variant = old ]; then envs=RAYKIN_SHADER_DIR=relb/old-shaders/shaders; else envs=RAYKIN_UNUSED=1; fi
    [ "$(elapsed)" -lt 540 ] && frame_rows "$variant" seed.txt relb/head "$envs" --scene seed-interior \
      --width 2560 --height 1440 --frames 24 --integrator auto
  done
done
echo "seed: $(elapsed) s" >> "$OUT/traced-by.txt"
cat "$OUT/seed.txt"; grep -A10 "### Mitsuba" "$OUT/summary.md"
