#!/usr/bin/env bash
# Device call 3 (d12e333): the Mitsuba side by side with Mitsuba's low-discrepancy sampler (ldsampler, the class of
# raykin's new sampler) on the four one-light static scenes (raykin's error curves compile no AOVs, so the film is
# stratified); then raykin's curves again with the film position independent (sobol/film-independent through
# RAYKIN_SHADER_DIR) against the same Mitsuba renders.
set -u
start=$(date +%s)
source scripts/gpu-unpack.sh final
export RAYKIN_COMMIT=d12e333 ASSETS=rel/assets RAYKIN_BIN=rel/final
scenes="--scene cornell --scene spheres --scene flight-helmet --scene env-lit"
MITSUBA_SAMPLER=ldsampler MITSUBA_SCENES="cornell spheres flight-helmet env-lit" timeout 380 bash scripts/gpu-mitsuba.sh "$OUT/ld" > /tmp/run.log 2>&1
echo "side by side: $(( $(date +%s) - start )) s"
grep -v warning /tmp/run.log | grep -v LowDiscrepancy | tail -n 30 > "$OUT/run-tail.log"
grep -A8 "time to equal error" "$OUT/ld/summary.md" | head -10
left=$(( 570 - ($(date +%s) - start) ))
echo "film-independent run with ${left} s left"
RAYKIN_SHADER_DIR=sobol/film-independent timeout "$left" rel/final bench --suite full $scenes --assets rel/assets \
  --parts errors --curve "16 spp" --mitsuba /tmp/mitsuba-export --out /tmp/fi --cache /tmp/bench-cache-fi > /tmp/fi.log 2>&1
tar czf "$OUT/film-independent.tgz" -C /tmp fi fi.log
grep -A8 "time to equal error" /tmp/fi/summary.md | head -10
echo "total: $(( $(date +%s) - start )) s"
