#!/usr/bin/env bash
# Same-call A/B of trace time and ray-casting rates on a device machine: each VARIANT (`binary` or
# `binary:shader-dir`, the binary under rel/ as rel/NAME.xz, the optional folder given to RAYKIN_SHADER_DIR;
# either followed by comma-separated bench options of that variant's own, e.g. `head,--integrator=wavefront`) runs
# the bench's frame loop on the bench scenes (SCENES, default "cornell flight-helmet spheres crowd"; BENCH_ARGS:
# more bench options, e.g. "--spp-per-frame 16"), variants alternating ROUNDS times. Writes $OUT/bench.log and
# $OUT/ab.txt (variant, round, scene, width, height, trace ms median, shading-free camera and diffuse bounce G
# rays/s) and prints each scene/size/variant mean. Carry .gl and rel; ASSETS (default shared/assets) holds the scenes.
# Usage: bash scripts/gpu-ab-frames.sh ROUNDS VARIANT...
set -u
rounds=$1; shift
scenes=()
for s in ${SCENES:-cornell flight-helmet spheres crowd}; do scenes+=(--scene "$s"); done
binaries=()
for v in "$@"; do spec=${v%%,*}; binaries+=("${spec%%:*}"); done
source "$(dirname "$0")/gpu-unpack.sh" "${binaries[@]}"
for round in $(seq "$rounds"); do
  for v in "$@"; do
    spec=${v%%,*}; own=()
    [[ $v == *,* ]] && IFS=, read -r -a own <<< "${v#*,}"
    b=${spec%%:*}; dir=/nonexistent
    [[ $spec == *:* ]] && dir=${spec#*:}
    w=$(mktemp -d)
    RAYKIN_SHADER_DIR=$dir rel/$b bench --suite full --parts frames --frames ${FRAMES:-40} ${BENCH_ARGS:-} "${own[@]}" "${scenes[@]}" \
      --assets "${ASSETS:-shared/assets}" --out "$w" --cache "$w/c" >> "$OUT/bench.log" 2>&1
    python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']: print('$v', $round, row.get('scene'), row.get('width'), row.get('height'), row.get('trace_ms_median', row.get('trace_ms')),
  row.get('raycast_camera_rays_per_s', 0) / 1e9, row.get('raycast_diffuse_rays_per_s', 0) / 1e9)
" >> "$OUT/ab.txt"
  done
done
awk '{k=$3" "$4" "$1; s[k]+=$6; c[k]+=$7; d[k]+=$8; n[k]++}
  END {for (k in s) printf "%s trace_ms %.4f camera_G %.3f diffuse_G %.3f\n", k, s[k]/n[k], c[k]/n[k], d[k]/n[k]}' "$OUT/ab.txt" | sort
