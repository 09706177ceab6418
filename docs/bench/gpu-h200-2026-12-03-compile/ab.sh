#!/usr/bin/env bash
# Device call (ab-1, ab-3): trace time before (2bed230) and after, two dev-profile binaries alternating twice.
exec bash scripts/gpu-ab-frames.sh 2 raykin-old raykin-new
