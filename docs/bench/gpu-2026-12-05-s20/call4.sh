#!/usr/bin/env bash
# Twentieth session, call 4: call3.sh again, the same binary (07cae21's code), on the next machine lent, for the
# call-to-call spread of the side by side's ratios (Mitsuba's own samples/s moved 0.8-1.1x between earlier calls).
exec bash docs/bench/gpu-2026-12-05-s20/call3.sh
