#!/usr/bin/env bash
# Thirtieth session, call 2. relb/head.xz = 0d7310a's refill with pass-throughs (call 1's binary refused to refill
# any scene with an alpha-blended material, so its seed-like interior rows, all 21.11 ms, never refilled).
# Waves forced, rays sorted, 2560x1440, 1 spp, depth 6: refill off and at 2048 and 4096 workgroups on the
# seed-like interior and the crowd; auto with refill off and on (2048) on both; the waves' rows again; then the static scenes that run in waves at 960x540, 16 spp (env-lit, many-lights) -> refill.txt:
# label, scene, width, trace ms median, frame ms median, form, rays sorted. Carry [".gl", "relb"].
set -u
source scripts/gpu-unpack.sh
rows() {
  local w; w=$(mktemp -d); local label=$1 envs=$2 scene=$3; shift 3
  [ "$(elapsed)" -lt 170 ] || return
  env $envs timeout 80 relb/head bench --suite full --parts frames --scene "$scene" "$@" \
    --frames 24 --assets relb/assets --out "$w" --cache "$w/c" > "$w/log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']:
    print('$label', row['scene'], row['width'], round(row['trace_ms_median'],3), round(row['frame_ms']['median'],3), row['integrator'], row.get('rays_sorted'))
" >> "$OUT/refill.txt" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
big="--width 2560 --height 1440"
waves() {
  for scene in seed-interior crowd; do
    rows sorted-off "RAYKIN_WAVE_SORT=on RAYKIN_WAVE_REFILL=off" $scene $big --integrator wavefront
    for g in 2048 4096; do
      rows sorted-$g "RAYKIN_WAVE_SORT=on RAYKIN_WAVE_REFILL=on RAYKIN_WAVE_REFILL_GROUPS=$g" $scene $big \
        --integrator wavefront
    done
  done
}
waves
for scene in seed-interior crowd; do
  rows auto-off "RAYKIN_WAVE_REFILL=off" $scene $big --integrator auto
  rows auto-2048 "RAYKIN_WAVE_REFILL=on RAYKIN_WAVE_REFILL_GROUPS=2048" $scene $big --integrator auto
done
waves
for scene in env-lit many-lights cornell; do
  rows waves-off "RAYKIN_WAVE_REFILL=off" $scene --width 960 --height 540 --spp-per-frame 16 --integrator wavefront
  rows waves-2048 "RAYKIN_WAVE_REFILL=on RAYKIN_WAVE_REFILL_GROUPS=2048" $scene --width 960 --height 540 \
    --spp-per-frame 16 --integrator wavefront
done
echo "refill: $(elapsed) s" >> "$OUT/refill.txt"
cat "$OUT/gpu.txt" "$OUT/refill.txt"; cat "$OUT/errors.txt" 2>/dev/null; true
