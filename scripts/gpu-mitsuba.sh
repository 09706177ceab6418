#!/usr/bin/env bash
# The Mitsuba 3 side by side on the lent GPU, in one call: export the bench's static scenes, render them with
# Mitsuba's cuda_ad_rgb variant (scripts/mitsuba-side-by-side.py), then raykin's error curves with Mitsuba's
# beside them (`raykin bench --parts errors --mitsuba`). Needs Dr.Jit's and a stripped Mitsuba's cp312 wheels
# unpacked on PYTHONPATH (docs/BENCHMARKS.md says how they were carried). Environment: MITSUBA_SCENES (default
# the static bench scenes), MITSUBA_REPEATS (timed renders per sample count, default 2), MITSUBA_VARIANT, MITSUBA_SAMPLER
# (default independent, Mitsuba's default; ldsampler is its low-discrepancy one), RAYKIN_INTEGRATOR (raykin's
# `--integrator` for its curves, default megakernel).
set -u
here="$(cd "$(dirname "$0")" && pwd)"
source "$here/gpu-common.sh"
# The device returns few files: everything is written under $work, packed into $out/side-by-side.tgz at the
# end, with summary.md and the logs beside it.
work=/tmp/gpu-mitsuba
mkdir -p "$work"
trap 'tar czf "$out/side-by-side.tgz" -C "$work" . ; cp "$work/bench/summary.md" "$out/" 2>/dev/null' EXIT
scenes="${MITSUBA_SCENES:-cornell spheres flight-helmet env-lit many-lights furnace grazing}"
export_dir=/tmp/mitsuba-export
scene_args=()
for s in $scenes; do scene_args+=(--scene "$s"); done
"$bin" bench --suite full "${scene_args[@]}" --assets "$assets" --export-mitsuba "$export_dir" \
  2>&1 | tee "$work/export.log"
python3 "$here/mitsuba-side-by-side.py" "$export_dir" --variant "${MITSUBA_VARIANT:-cuda_ad_rgb}" \
  --repeats "${MITSUBA_REPEATS:-2}" --sampler "${MITSUBA_SAMPLER:-independent}" 2>&1 | grep -v DeprecationWarning | tee "$work/mitsuba.log"
for s in $scenes; do
  cp "$export_dir/$s/mitsuba.json" "$work/mitsuba-$s.json" 2>/dev/null
done
"$bin" bench --suite full "${scene_args[@]}" --assets "$assets" --parts errors --curve "16 spp" \
  --integrator "${RAYKIN_INTEGRATOR:-megakernel}" --mitsuba "$export_dir" --out "$work/bench" --cache /tmp/bench-cache 2>&1 | tee "$work/bench.log"
