#!/usr/bin/env bash
# Issue 17's lavapipe target, both readings: each binary renders the Cornell box (default sky, depth 6) at 128x128
# with SPP samples (wall time including start-up, the figure of earlier sessions) and at 16x16 with 1 sample
# (start-up alone: instance, scene, kernels); steady samples/s = 128 x 128 x SPP / (the first - the second).
# Binaries alternate ROUNDS times; prints and appends to OUT/target.txt.
#   bash scripts/lavapipe-target.sh OUT ROUNDS SPP NAME=BIN ...
set -u
out=$1 rounds=$2 spp=$3; shift 3
export XDG_RUNTIME_DIR=/tmp
scene=${ASSETS:-../shared/assets}/CornellBox/CornellBox.glb
mkdir -p "$out"
wall() { /usr/bin/time -f %e "$@" 2>&1 >/dev/null | tail -1; }
for r in $(seq "$rounds"); do
  for v in "$@"; do
    name=${v%%=*} bin=${v#*=}
    start=$(wall "$bin" render "$scene" --width 16 --height 16 --spp 1 --out "$out/$name-start.exr")
    total=$(wall "$bin" render "$scene" --width 128 --height 128 --spp "$spp" --out "$out/$name.exr")
    python3 -c "
s, t = $start, $total; n = 128 * 128 * $spp
print(f'$name round $r: {t:.2f} s wall ({n / t / 1e6:.3f} M samples/s), start-up {s:.2f} s, steady {n / (t - s) / 1e6:.3f} M samples/s')
" | tee -a "$out/target.txt"
  done
done
