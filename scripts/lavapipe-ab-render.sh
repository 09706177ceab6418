#!/usr/bin/env bash
# A/B on a CPU adapter (lavapipe): `raykin render SCENE --width 128 --height 128 --spp SPP` per variant, alternating
# ROUNDS times; prints and appends to OUT/ab.txt each render's "wrote" line.
#   bash scripts/lavapipe-ab-render.sh OUT ROUNDS SPP NAME=BIN[:SHADER_DIR[:ENV=V]] ...
# SHADER_DIR: kernels through RAYKIN_SHADER_DIR (empty: built in); ENV=V: one environment switch (e.g.
# RAYKIN_SOLE_INSTANCE=off). SCENE defaults to the Cornell box of ASSETS (default ../shared/assets); EXTRA: more
# `render` flags.
set -u
out=$1 rounds=$2 spp=$3; shift 3
export XDG_RUNTIME_DIR=/tmp
scene=${SCENE:-${ASSETS:-../shared/assets}/CornellBox/CornellBox.glb}
extra=${EXTRA:-}
mkdir -p "$out"
for r in $(seq "$rounds"); do
  for v in "$@"; do
    name=${v%%=*}; rest=${v#*=}
    IFS=: read -r bin dir env <<< "$rest"
    line=$(env ${env:+"$env"} RAYKIN_SHADER_DIR="${dir:-}" "$bin" render "$scene" --width 128 --height 128 --spp "$spp" $extra --out "$out/$name.exr" 2>&1 | grep "wrote")
    echo "$name $r $line" | tee -a "$out/ab.txt"
  done
done
