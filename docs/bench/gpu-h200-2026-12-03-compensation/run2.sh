#!/usr/bin/env bash
# Device call 2 (H200): the Mitsuba 3 side by side (scripts/gpu-mitsuba.sh) with d0c26d3's binary (NEE leaves a
# uniform map to BSDF sampling and samples concentrated maps MIS-compensated; the trace kernel without the
# denoisers' inputs where nothing reads them). Carry .gl, rel (raykin-final.xz) and .whl (Dr.Jit 1.5.0's cp312
# wheel, mitsuba-strip.tar.xz).
set -u
OUT=${OUT:-gpu-out}; mkdir -p "$OUT"
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl || exit 1
tar -C /tmp -xJf .whl/mitsuba-strip.tar.xz
export PYTHONPATH=/tmp/site
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
(cd rel && xz -dkf raykin-final.xz && chmod +x raykin-final)
RAYKIN_BIN=rel/raykin-final bash scripts/gpu-mitsuba.sh "$OUT"
