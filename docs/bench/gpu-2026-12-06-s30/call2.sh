#!/usr/bin/env bash
# Thirtieth session, call 2. relb/head.xz = faef3f2: 0d7310a's refill with pass-throughs (call 1's binary refused
# to refill any scene with an alpha-blended material, so its seed-like interior rows, all 21.11 ms, never
# refilled). 2560x1440, 1 spp, depth 6, 24 frames: waves forced and sorted, refill off and at 2048 workgroups, on
# the seed-like interior and the crowd, two rounds; then auto with refill on (2048) and off -> refill.txt: label,
# scene, width, trace ms median, frame ms median, form, rays sorted. Short: the session's device time was nearly
# spent on starts that got no machine. Carry [".gl", "relb"].
set -u
source scripts/gpu-unpack.sh
rows() {
  local w; w=$(mktemp -d); local label=$1 envs=$2 scene=$3; shift 3
  [ "$(elapsed)" -lt 50 ] || return
  env $envs timeout 30 relb/head bench --suite full --parts frames --scene "$scene" "$@" \
    --frames 24 --assets relb/assets --out "$w" --cache "$w/c" > "$w/log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']:
    print('$label', row['scene'], row['width'], round(row['trace_ms_median'],3), round(row['frame_ms']['median'],3), row['integrator'], row.get('rays_sorted'))
" >> "$OUT/refill.txt" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
big="--width 2560 --height 1440"
for round in 1 2; do
  for scene in seed-interior crowd; do
    rows sorted-off "RAYKIN_WAVE_SORT=on RAYKIN_WAVE_REFILL=off" $scene $big --integrator wavefront
    rows sorted-2048 "RAYKIN_WAVE_SORT=on RAYKIN_WAVE_REFILL=on RAYKIN_WAVE_REFILL_GROUPS=2048" $scene $big \
      --integrator wavefront
  done
done
for scene in seed-interior crowd; do
  rows auto-2048 "RAYKIN_WAVE_REFILL=on RAYKIN_WAVE_REFILL_GROUPS=2048" $scene $big --integrator auto
  rows auto-off "RAYKIN_WAVE_REFILL=off" $scene $big --integrator auto
done
echo "refill: $(elapsed) s" >> "$OUT/refill.txt"
cat "$OUT/gpu.txt" "$OUT/refill.txt"; cat "$OUT/errors.txt" 2>/dev/null; true
