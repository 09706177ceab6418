#!/usr/bin/env bash
# Twenty-ninth session, call 3. relb/head.xz = bc82a15 (the deforming meshes' wide trees; RAYKIN_WIDE_DEFORMED=off
# keeps their BVH2s). The real-time path (the viewer's offscreen frame loop, `--mode realtime`, 2560x1440, 1 spp,
# depth 6, 300 frames) on the crowd and on the seed-like interior, the wide trees on and off, two rounds ->
# realtime.txt: label, scene, round, GPU trace ms median / p90, the real-time frame's GPU total median, the CPU
# frame ms median. Carry [".gl", "relb"].
set -u
source scripts/gpu-unpack.sh
run() {
  local label=$1 envs=$2 scene=$3 round=$4 w; w=$(mktemp -d)
  [ "$(elapsed)" -lt 420 ] || return
  env $envs timeout 120 relb/head view "$scene" --assets relb/assets --offscreen --frames 300 \
    --image-size 2560x1440 --spp-per-frame 1 --max-depth 6 --no-settings --mode realtime \
    --report "$w/r.json" > "$w/log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/r.json')); g=r['gpu_ms']; c=r['cpu_ms']
print('$label', '$scene', $round, round(g['trace']['median'],3), round(g['trace']['p90'],3), round(g['realtime_frame_total']['median'],3), round(c['frame']['median'],3))
" >> "$OUT/realtime.txt" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
for round in 1 2; do
  for scene in crowd seed-interior; do
    run wide RAYKIN_WIDE_DEFORMED=on $scene $round
    run bvh2 RAYKIN_WIDE_DEFORMED=off $scene $round
  done
done
echo "realtime: $(elapsed) s" >> "$OUT/realtime.txt"
cat "$OUT/gpu.txt" "$OUT/realtime.txt"; cat "$OUT/errors.txt" 2>/dev/null; true
