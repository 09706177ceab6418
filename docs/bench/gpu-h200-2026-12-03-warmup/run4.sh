#!/usr/bin/env bash
# Device call 4 (H200): the Mitsuba 3 side by side again (scripts/gpu-mitsuba.sh) with this commit's bench (each
# timed curve after 0.6 s of untimed work) and the script's centred scenes. Carry .gl, rel (raykin-new.xz) and
# .whl (Dr.Jit 1.5.0's cp312 wheel, mitsuba-strip.tar.xz).
set -u
OUT=${OUT:-gpu-out}; mkdir -p "$OUT"
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl || exit 1
tar -C /tmp -xJf .whl/mitsuba-strip.tar.xz
export PYTHONPATH=/tmp/site
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
(cd rel && xz -dkf raykin-new.xz && chmod +x raykin-new)
RAYKIN_BIN=rel/raykin-new bash scripts/gpu-mitsuba.sh "$OUT"
