#!/usr/bin/env bash
# This 2-core machine, lavapipe: the scene read from textures (the default on CPU adapters) against storage
# buffers (RAYKIN_SCENE_READS=buffers), same binary, alternating ROUNDS times: the bench's frame loop (CPU
# adapter sizes: 1920x1080 and 2560x1440 / 16), trace kernel median of FRAMES frames (GPU timestamps).
# Usage: ab.sh BINARY ASSETS OUT [ROUNDS] [FRAMES] [VARIANT=SHADER_DIR ...]: a variant runs the textures form
# with RAYKIN_SHADER_DIR set (kernel ablations).
set -u
bin=$1 assets=$2 out=$3 rounds=${4:-2} frames=${5:-12}
shift 5 2>/dev/null || shift $#
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
mkdir -p "$out"
scenes=(--scene cornell --scene flight-helmet --scene spheres --scene crowd)
one() { # form round
  local form=$1 round=$2 dir=""
  case $form in *=*) dir=${form#*=}; form=${form%%=*} ;; esac
  local reads=textures; [ "$form" = buffers ] && reads=buffers
  local w; w=$(mktemp -d)
  RAYKIN_SCENE_READS=$reads RAYKIN_SHADER_DIR=$dir "$bin" bench --suite full --parts frames --frames "$frames" \
    "${scenes[@]}" --assets "$assets" --out "$w" --cache "$w/c" >> "$out/bench.log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']: print('$form', $round, row.get('scene'), row.get('width'), row.get('height'), row.get('trace_ms_median'))
" | tee -a "$out/ab.txt"
  rm -rf "$w"
}
for round in $(seq "$rounds"); do
  for form in buffers textures "$@"; do one "$form" "$round"; done
done
awk '{k=$3" "$4"x"$5" "$1; s[k]+=$6; n[k]++} END {for (k in s) printf "%s trace_ms %.2f (n=%d)\n", k, s[k]/n[k], n[k]}' \
  "$out/ab.txt" | sort | tee "$out/summary.txt"
