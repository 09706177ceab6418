#!/usr/bin/env bash
# A/B on lavapipe: `raykin render SCENE 128x128 --spp SPP` per variant (NAME=BIN[:SHADER_DIR[:ENV=V]]), alternating ROUNDS times.
set -u
out=$1 rounds=$2 spp=$3; shift 3
export XDG_RUNTIME_DIR=/tmp
scene=${SCENE:-/work/shared/assets/CornellBox/CornellBox.glb}
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
