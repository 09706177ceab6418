#!/usr/bin/env bash
# For the next device call: the Mitsuba 3 side by side (scripts/gpu-mitsuba.sh) on all five static bench scenes
# with raykin's default integrator (auto), on the H200 of issue 17's targets if one is lent. The nineteenth
# session ran it on H100s only (docs/bench/gpu-2026-12-05-s19/call3.sh; docs/BENCHMARKS.md, "Mitsuba 3 side by
# side"); MITSUBA_REPEATS=1 keeps the five scenes within about 250 s. Build: `cargo build --release -p raykin &&
# mkdir -p relb && strip -o relb/head target/release/raykin && xz -T2 -6 -f relb/head`; relb/assets/{CornellBox,FlightHelmet,MetalRoughSpheresNoTextures} from ../shared/assets;
# .gl (the device README's loader recipe); .whl: Dr.Jit 1.5.0's cp312 wheel and `KEEP_DATA= bash
# scripts/strip-mitsuba-wheel.sh mitsuba-3.9.1-*.whl .whl/mitsuba-strip.tar.xz` (without srgb.coeff, which the rgb
# variants never open, the tree fits the 64 MiB limit). Carry [".gl", "relb", ".whl"]; set RAYKIN_COMMIT.
set -u
source scripts/gpu-unpack.sh
MITSUBA_REPEATS=${MITSUBA_REPEATS:-1} ASSETS=relb/assets RAYKIN_BIN=relb/head RAYKIN_INTEGRATOR=auto \
  bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
echo "side by side: $(elapsed) s"
grep -v warning /tmp/run.log | tail -n 30 > "$OUT/run-tail.log"
grep -h "traced by" /tmp/gpu-mitsuba/bench.log > "$OUT/traced-by.txt"
grep -A12 "time to equal error" "$OUT/summary.md" | head -20
