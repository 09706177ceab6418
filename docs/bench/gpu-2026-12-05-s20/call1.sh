#!/usr/bin/env bash
# Twentieth session, call 1 (relb/head.xz = the stripped release build of the commit in RAYKIN_COMMIT): (a) the
# wavefront's fused form (RAYKIN_WAVE_FUSED=on: one kernel per bounce traces the path ray, shades and traces the
# shadow ray) against the split form at the error part's 960x540, 16 spp per frame, one wave of 2^23 paths;
# (b) the static merge's tree: obvhs presets with and without spatial splits (RAYKIN_STATIC_BVH) on FlightHelmet
# (megakernel), the spheres (waves) and the seed-like interior (waves, 2560x1440, 1 spp). The bench's frame loop,
# two rounds, variants alternating -> frames.txt; the merge's build lines -> merge.txt. Carry [".gl", "relb"];
# relb/assets holds CornellBox, FlightHelmet, MetalRoughSpheresNoTextures, CesiumMan, Fox.
set -u
source scripts/gpu-unpack.sh
export RAYKIN_COMMIT=${RAYKIN_COMMIT:-unknown}
frames() {  # label, environment assignment (or -), integrator, bench options...
  local w; w=$(mktemp -d); local label=$1 env=$2 integrator=$3; shift 3
  [ "$env" = - ] && env=RAYKIN_NONE=1
  env "$env" RUST_LOG=warn,raykin::render::gpu_scene::static_merge=info relb/head bench --suite full \
    --parts frames --frames 24 --integrator "$integrator" "$@" --assets relb/assets --out "$w" --cache "$w/c" \
    > "$w/log" 2>&1
  grep "static merge" "$w/log" | sed "s/^/$label /" >> "$OUT/merge.txt"
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']: print('$label', row['scene'], row['width'], row['spp_per_frame'], row['trace_ms_median'], row['integrator'])
" >> "$OUT/frames.txt" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
small=(--width 960 --height 540 --spp-per-frame 16)
for round in 1 2; do
  [ "$(elapsed)" -gt 480 ] && break
  frames split - wavefront --scene cornell --scene flight-helmet --scene spheres --scene env-lit "${small[@]}"
  frames fused RAYKIN_WAVE_FUSED=on wavefront --scene cornell --scene flight-helmet --scene spheres --scene env-lit "${small[@]}"
  for tree in medium medium-split slow-split veryslow-split; do
    [ "$(elapsed)" -gt 480 ] && break 2
    frames "tree-$tree" RAYKIN_STATIC_BVH=$tree megakernel --scene flight-helmet "${small[@]}"
    frames "tree-$tree" RAYKIN_STATIC_BVH=$tree wavefront --scene spheres "${small[@]}"
    frames "tree-$tree" RAYKIN_STATIC_BVH=$tree wavefront --scene seed-interior --width 2560 --height 1440
  done
done
echo "total: $(elapsed) s" | tee -a "$OUT/frames.txt"
cat "$OUT/frames.txt"
sort -u "$OUT/merge.txt" | head -40
