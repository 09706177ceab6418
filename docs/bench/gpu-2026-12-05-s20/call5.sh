#!/usr/bin/env bash
# Twentieth session, call 5: call3.sh's side by side with the median of three Mitsuba renders per count, without
# the frame loop: calls 3 and 4 timed Mitsuba's FlightHelmet at 904 and 1152 M samples/s with one render each.
MITSUBA_REPEATS=3 SIDE_BY_SIDE_SECONDS=480 FRAMES=off exec bash docs/bench/gpu-2026-12-05-s20/call3.sh
