#!/usr/bin/env bash
# A/B on a CPU adapter (lavapipe): the bench's frame loop (the CPU adapter's sizes) on the Cornell box, FlightHelmet,
# the spheres and the crowd, trace-kernel medians from timestamps, variants alternating ROUNDS times; rows in
# OUT/ab.txt, means per scene, size and variant in OUT/summary.txt.
#   bash scripts/lavapipe-ab-frames.sh BIN OUT ROUNDS FRAMES NAME=SHADER_DIR[:ENV=V] ...
# SHADER_DIR: kernels through RAYKIN_SHADER_DIR ("" = built in); ENV=V: one environment switch; ASSETS: the
# assets folder (default ../shared/assets).
set -u
bin=$1 out=$2 rounds=$3 frames=$4; shift 4
export XDG_RUNTIME_DIR=/tmp
mkdir -p "$out"
for r in $(seq "$rounds"); do
  for v in "$@"; do
    name=${v%%=*}; rest=${v#*=}; IFS=: read -r dir env <<< "$rest"; w=$(mktemp -d)
    env ${env:+"$env"} RAYKIN_SHADER_DIR="$dir" "$bin" bench --suite full --parts frames --frames "$frames" --scene cornell --scene flight-helmet --scene spheres --scene crowd \
      --assets "${ASSETS:-../shared/assets}" --out "$w" --cache "$w/c" >> "$out/bench.log" 2>&1
    python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']: print('$name', $r, row.get('scene'), row.get('width'), row.get('height'), row.get('trace_ms_median'))" | tee -a "$out/ab.txt"
    rm -rf "$w"
  done
done
awk '{k=$3" "$4"x"$5" "$1; s[k]+=$6; n[k]++} END {for (k in s) printf "%s trace_ms %.2f (n=%d)\n", k, s[k]/n[k], n[k]}' "$out/ab.txt" | sort | tee "$out/summary.txt"
