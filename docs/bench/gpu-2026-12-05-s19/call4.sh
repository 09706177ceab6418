#!/usr/bin/env bash
# Nineteenth session, call 4 (relb/head.xz = f47dbc5's stripped release build): where a wave's time goes, per stage
# (`RAYKIN_WAVE_PROFILE=on`: the first wave of each dispatch one compute pass per stage, each timed), with
# `--integrator wavefront` on the four static bench scenes at the error part's 960x540 and 16 spp per frame (one
# wave of 8.4 M paths), and the seed-like interior at 2560x1440, 1 spp -> profile.txt (the last frames' lines per
# scene). Carry [".gl", "relb"]; relb/assets holds CornellBox, FlightHelmet, MetalRoughSpheresNoTextures,
# CesiumMan, Fox.
set -u
start=$(date +%s)
elapsed() { echo $(( $(date +%s) - start )); }
source scripts/gpu-unpack.sh
(cd relb && xz -dkf head.xz && chmod +x head)
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
export RAYKIN_COMMIT=f47dbc5
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv > "$OUT/gpu.txt"
profile() {  # scene, bench options...
  local scene=$1; shift
  local w; w=$(mktemp -d)
  RUST_LOG=warn,raykin::render::passes::wavefront=info RAYKIN_WAVE_PROFILE=on relb/head bench --suite full \
    --parts frames --frames 20 --integrator wavefront --scene "$scene" "$@" --assets relb/assets --out "$w" \
    --cache "$w/c" > /tmp/profile-$scene.log 2>&1
  echo "$scene $*" >> "$OUT/profile.txt"
  grep "wavefront profile" /tmp/profile-$scene.log | tail -n 3 >> "$OUT/profile.txt"
}
for scene in cornell flight-helmet spheres env-lit; do
  [ "$(elapsed)" -gt 200 ] && break
  profile "$scene" --width 960 --height 540 --spp-per-frame 16
done
[ "$(elapsed)" -lt 230 ] && profile seed-interior --width 2560 --height 1440
echo "total: $(elapsed) s" >> "$OUT/profile.txt"
cat "$OUT/profile.txt"
