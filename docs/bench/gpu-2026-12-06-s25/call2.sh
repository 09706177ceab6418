#!/usr/bin/env bash
# Twenty-fifth session, call 2. relb/head.xz = the two new bench scenes of issue 17's scene classes (`furnace`: the
# white furnace; `grazing`: grazing light at 1e4 coordinates) and Arvo's spherical-triangle sampling without GPU
# asin (the sub-area from the solid angle: shaders/sampling.wgsl). relb/old-shaders = 0b270ad's kernels (the
# sampling before), run through RAYKIN_SHADER_DIR. Parts:
# 1. the Mitsuba 3 side by side of the seven static scenes (`--integrator auto`, the median of three Mitsuba renders
#    per count) -> summary.md, traced-by.txt;
# 2. the grazing scene's error part with the old kernels against the same Mitsuba renders: whether the NVIDIA
#    driver's asin also left its light short (the references' mean ratio) -> old-grazing.md;
# 3. trace ms of the old and the new kernels (the frame loop, 960x540, 16 spp a frame, two rounds alternating) on
#    the Cornell box, many-lights and the grazing scene -> frames.txt.
# Made by `bash scripts/gpu-pack.sh --mitsuba` and `git archive 0b270ad shaders | tar -x -C relb/old-shaders`;
# carry [".gl", "relb", ".whl"].
set -u
source scripts/gpu-unpack.sh
MITSUBA_REPEATS=3 ASSETS=relb/assets RAYKIN_BIN=relb/head RAYKIN_INTEGRATOR=auto timeout 420 \
  bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
grep -h "traced by" /tmp/gpu-mitsuba/bench.log > "$OUT/traced-by.txt"
cp /tmp/gpu-mitsuba/mitsuba.log "$OUT/" 2>/dev/null
echo "side by side: $(elapsed) s" >> "$OUT/traced-by.txt"
RAYKIN_SHADER_DIR=relb/old-shaders/shaders timeout 90 relb/head bench --suite full --scene grazing --assets relb/assets \
  --parts errors --curve "16 spp" --integrator auto --mitsuba /tmp/mitsuba-export --out /tmp/old-grazing \
  --cache /tmp/old-cache > /tmp/old-grazing.log 2>&1
grep -A4 "Mitsuba 3 side by side" /tmp/old-grazing/summary.md > "$OUT/old-grazing.md" || tail -5 /tmp/old-grazing.log > "$OUT/old-grazing.md"
echo "old grazing: $(elapsed) s" >> "$OUT/traced-by.txt"
for round in 1 2; do
  for variant in old new; do
    if [ $variant = old ]; then envs=RAYKIN_SHADER_DIR=relb/old-shaders/shaders; else envs=RAYKIN_UNUSED=1; fi
    frame_rows "$variant" frames.txt relb/head "$envs" --scene cornell --scene many-lights --scene grazing \
      --width 960 --height 540 --spp-per-frame 16 --frames 24 --integrator auto
  done
done
echo "frames: $(elapsed) s" >> "$OUT/traced-by.txt"
cat "$OUT/frames.txt" "$OUT/old-grazing.md"; tail -11 "$OUT/summary.md"
