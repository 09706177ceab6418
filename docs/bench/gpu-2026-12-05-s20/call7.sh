#!/usr/bin/env bash
# Twentieth session, call 7, scripted but not run (too little device time was left): call5.sh's side by side (the
# median of three Mitsuba renders per count) on whichever card the status offers (it offered an H200), cut at 230 s.
MITSUBA_REPEATS=3 SIDE_BY_SIDE_SECONDS=230 FRAMES=off exec bash docs/bench/gpu-2026-12-05-s20/call3.sh
