#!/usr/bin/env bash
# Device call (prediction for merging static meshes into one BLAS): FlightHelmet as shipped (six meshes, six
# BLASes under the TLAS, all overlapping) against the same file with its six primitives in one mesh (one BLAS;
# made by probe-merge.py), same binary, same automatic camera and sky, alternating three rounds; then one round
# at 16 spp per frame. Carry .gl and rel (rel/raykin-w.xz, rel/assets/FlightHelmet/glTF/*).
set -u
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
(cd rel && xz -dkf raykin-w.xz && chmod +x raykin-w)
nvidia-smi --query-gpu=name,clocks.sm,clocks.mem --format=csv > "$OUT/gpu.txt"
dir=rel/assets/FlightHelmet/glTF
run() { # label spp-per-frame scene...
  local label=$1 spp=$2; shift 2
  local w; w=$(mktemp -d)
  args=(); for s in "$@"; do args+=(--scene "$dir/$s.gltf"); done
  rel/raykin-w bench --suite full --parts frames --frames 60 --spp-per-frame "$spp" "${args[@]}" \
    --out "$w" --cache "$w/c" >> "$OUT/bench.log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']: print('$label', $spp, row.get('scene'), row.get('width'), row.get('height'), row.get('trace_ms_median'),
  row.get('raycast_camera_rays_per_s', 0) / 1e9, row.get('raycast_diffuse_rays_per_s', 0) / 1e9)
" >> "$OUT/ab.txt"
}
for round in 1 2 3; do
  run r$round 1 FlightHelmet FlightHelmetMerged
  run r$round 1 FlightHelmetMerged FlightHelmet
done
run s1 16 FlightHelmet FlightHelmetMerged
run s2 16 FlightHelmetMerged FlightHelmet
awk '{k=$2" "$3" "$4"x"$5; s[k]+=$6; c[k]+=$7; d[k]+=$8; n[k]++}
  END {for (k in s) printf "spp %s trace_ms %.4f camera_G %.3f diffuse_G %.3f (n=%d)\n", k, s[k]/n[k], c[k]/n[k], d[k]/n[k], n[k]}' "$OUT/ab.txt" | sort
