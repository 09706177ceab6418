#!/usr/bin/env bash
# Device call: the Mitsuba 3 side by side (scripts/gpu-mitsuba.sh) with the merged static tree (binary of
# e80cc51 at opt-level 3, stripped, rel/raykin-m.xz; its default is `--static-bvh merged`), then, while the
# call has time left, two more rounds of ab.sh (merged against per-mesh wide trees, same binary). Carry .gl,
# rel (the binary, rel/assets) and .whl (Dr.Jit 1.5.0's cp312 wheel and mitsuba-strip.tar.xz, made by
# scripts/strip-mitsuba-wheel.sh from Mitsuba 3.9.1's cp312 wheel).
set -u
start=$(date +%s)
here=docs/bench/gpu-h200-2026-12-04-merge
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/drjit-*.whl || exit 1
tar -C /tmp -xJf .whl/mitsuba-strip.tar.xz
export PYTHONPATH=/tmp/site
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
(cd rel && xz -dkf raykin-m.xz && chmod +x raykin-m)
mkdir -p "$OUT/mitsuba"
RAYKIN_COMMIT=e80cc51 ASSETS=rel/assets RAYKIN_BIN=rel/raykin-m bash scripts/gpu-mitsuba.sh "$OUT/mitsuba" > "$OUT/mitsuba/run.log" 2>&1
echo "side by side: $(( $(date +%s) - start )) s"
grep -A12 "time to equal error" "$OUT/mitsuba/summary.md" | head -20
if (( $(date +%s) - start < 330 )); then
  mkdir -p "$OUT/ab"; OUT="$OUT/ab" bash "$here/ab.sh" 2 | tail -40
fi
