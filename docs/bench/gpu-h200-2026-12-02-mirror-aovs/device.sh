#!/usr/bin/env bash
# Device call: trace time of the path kernel before (980b748) and after (476777a: AOVs follow mirrors), alternating twice.
SCENES="cornell flight-helmet spheres" exec bash scripts/gpu-ab-frames.sh 2 raykin raykin-aov raykin-aov2
