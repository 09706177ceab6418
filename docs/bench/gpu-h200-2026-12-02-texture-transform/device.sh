#!/usr/bin/env bash
# Device call: trace time before (711cae3) and after (bd4e9d4: texture-info entries of 48 B with UV rows), alternating twice.
exec bash scripts/gpu-ab-frames.sh 2 raykin raykin-tt
