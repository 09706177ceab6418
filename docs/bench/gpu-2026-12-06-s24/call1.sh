#!/usr/bin/env bash
# Twenty-fourth session, call 1: the twenty-third session's head (1e14bbe: the specialised kernels with the
# wider folding of e7d3ce2, the fallback warning of feb52b5 and the review's 1e14bbe), which never ran on a GPU.
# The parts of ../gpu-2026-12-06-s23/call2.sh: images (specialised against WGSL, byte for byte, 128x128, 16 spp),
# startup, frames (off / on, the five static scenes in both forms and the seed-like interior), then the Mitsuba 3
# side by side of the five static scenes until CALL_UNTIL. Made by `bash scripts/gpu-pack.sh --mitsuba`; carry
# [".gl", "relb", ".whl"].
export RAYKIN_COMMIT=${RAYKIN_COMMIT:-1e14bbe}
PARTS=${PARTS:-images startup frames side_by_side} CALL_UNTIL=${CALL_UNTIL:-570} \
  bash docs/bench/gpu-2026-12-06-s23/call2.sh
