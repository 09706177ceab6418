#!/usr/bin/env bash
# Device calls: trace time of the environment-map change on the map-lit and sky-lit static scenes, binaries
# alternating 3 times: uniform points inside cells (raykin-a, f141b89) against bilinear everywhere (raykin-b,
# 655ade0) and bilinear only for maps with contrasty cells (raykin-c, the commit after 5c1b632). The first call
# ran a and b; the second a, b and c.
SCENES="env-lit flight-helmet spheres" exec bash scripts/gpu-ab-frames.sh 3 raykin-a raykin-b ${VARIANT_C:-raykin-c}
