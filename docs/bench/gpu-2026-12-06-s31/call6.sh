#!/usr/bin/env bash
# Thirty-first session, call 6 (call 4 again, on an H200). relb/head.xz = 72fb682 again: the Cornell box's side by side with Mitsuba 3
# (auto, the median of three Mitsuba renders per count) with the waves' refill at 4096 workgroups (the default to
# be: RAYKIN_WAVE_REFILL=on RAYKIN_WAVE_REFILL_GROUPS=4096), then raykin's curves again with refill off against
# the same Mitsuba renders -> summary.md (on), summary-off.md (off), traced-by.txt.
# Carry [".gl", "relb", ".whl"].
set -u
source scripts/gpu-unpack.sh
export RAYKIN_WAVE_REFILL=on RAYKIN_WAVE_REFILL_GROUPS=4096
MITSUBA_SCENES=cornell MITSUBA_REPEATS=3 ASSETS=relb/assets RAYKIN_BIN=relb/head RAYKIN_INTEGRATOR=auto \
  timeout 300 bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
grep -h "traced by" /tmp/gpu-mitsuba/bench.log > "$OUT/traced-by.txt"
cp /tmp/gpu-mitsuba/mitsuba.log "$OUT/" 2>/dev/null
echo "side by side: $(elapsed) s" >> "$OUT/traced-by.txt"
RAYKIN_WAVE_REFILL=off timeout 200 relb/head bench --suite full --scene cornell --assets relb/assets --parts errors \
  --curve "16 spp" --integrator auto --mitsuba /tmp/mitsuba-export --out /tmp/bench-off --cache /tmp/bench-cache \
  > /tmp/off.log 2>&1
grep -h "traced by" /tmp/off.log | sed 's/^/off: /' >> "$OUT/traced-by.txt"
cp /tmp/bench-off/summary.md "$OUT/summary-off.md"
echo "off: $(elapsed) s" >> "$OUT/traced-by.txt"
cat "$OUT/gpu.txt" "$OUT/traced-by.txt"; grep -A4 "### Mitsuba" "$OUT/summary.md" "$OUT/summary-off.md"; true
