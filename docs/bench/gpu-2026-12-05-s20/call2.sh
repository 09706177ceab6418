#!/usr/bin/env bash
# Twentieth session, call 2 (relb/head.xz = the stripped release build of the commit in RAYKIN_COMMIT): the static
# merge's tree, separating obvhs's VerySlow preset from its spatial splits, and two stronger settings
# (RAYKIN_STATIC_REINSERTION: reinsertion batch ratio 3; RAYKIN_STATIC_SEARCH: PLOC search distance 32), on
# FlightHelmet (megakernel), the spheres (waves), the seed-like interior (waves, 2560x1440, 1 spp), and the Cornell
# box and env-lit (waves) for the default against VerySlow with splits. The bench's frame loop, two rounds,
# variants alternating -> frames.txt; the merge's build lines -> merge.txt. Carry [".gl", "relb"].
set -u
source scripts/gpu-unpack.sh
export RAYKIN_COMMIT=${RAYKIN_COMMIT:-unknown}
frames() {  # label, environment assignments (comma-separated, or -), integrator, bench options...
  local w; w=$(mktemp -d); local label=$1 envs=$2 integrator=$3; shift 3
  [ "$envs" = - ] && envs=RAYKIN_NONE=1
  env ${envs//,/ } RUST_LOG=warn,raykin::render::gpu_scene::static_merge=info relb/head bench --suite full \
    --parts frames --frames 24 --integrator "$integrator" "$@" --assets relb/assets --out "$w" --cache "$w/c" \
    > "$w/log" 2>&1
  grep "static merge" "$w/log" | sed "s/^/$label /" >> "$OUT/merge.txt"
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']: print('$label', row['scene'], row['width'], row['spp_per_frame'], row['trace_ms_median'], row['integrator'])
" >> "$OUT/frames.txt" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
small=(--width 960 --height 540 --spp-per-frame 16)
trees=("medium RAYKIN_STATIC_BVH=medium" "veryslow RAYKIN_STATIC_BVH=veryslow"
  "veryslow-split RAYKIN_STATIC_BVH=veryslow-split"
  "reinsert3-split RAYKIN_STATIC_BVH=veryslow-split,RAYKIN_STATIC_REINSERTION=3"
  "search32-split RAYKIN_STATIC_BVH=veryslow-split,RAYKIN_STATIC_SEARCH=32")
for round in 1 2; do
  for tree in "${trees[@]}"; do
    set -- $tree
    [ "$(elapsed)" -gt 480 ] && break 2
    frames "$1" "$2" megakernel --scene flight-helmet "${small[@]}"
    frames "$1" "$2" wavefront --scene spheres "${small[@]}"
    frames "$1" "$2" wavefront --scene seed-interior --width 2560 --height 1440
  done
  for tree in "${trees[0]}" "${trees[2]}"; do
    set -- $tree
    frames "$1" "$2" wavefront --scene cornell --scene env-lit "${small[@]}"
  done
done
echo "total: $(elapsed) s" | tee -a "$OUT/frames.txt"
cat "$OUT/frames.txt"
sort -u "$OUT/merge.txt" | sed 's/raykin: note: static merge: //' | head -40
