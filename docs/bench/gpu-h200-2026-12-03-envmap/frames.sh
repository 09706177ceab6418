#!/usr/bin/env bash
# Device call: trace time of the environment-map change, uniform (raykin-a, f141b89) against bilinear (raykin-b,
# 655ade0) sampling inside a cell, on the map-lit and sky-lit static scenes, the binaries alternating 3 times.
SCENES="env-lit flight-helmet spheres" exec bash scripts/gpu-ab-frames.sh 3 raykin-a raykin-b
