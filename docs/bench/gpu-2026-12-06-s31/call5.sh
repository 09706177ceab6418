#!/usr/bin/env bash
# Thirty-first session, call 5. relb/head.xz = c2a3b53 (refill on by default at 4096 workgroups; shade reads the
# last scattering vertex only to weigh an emitter, the hit's t only in a medium); rel/base.xz = 72fb682 run with
# RAYKIN_WAVE_REFILL=on RAYKIN_WAVE_REFILL_GROUPS=4096 (d6e55e1's default, without the trimmed reads).
# frames.txt (frame_rows): base / head alternating, two rounds: cornell, env-lit, many-lights at 960x540, 16 spp a
#    frame, waves forced unsorted; the seed-like interior and the crowd at 2560x1440, 1 spp, auto.
# Carry [".gl", "relb", "rel"] (with the Mitsuba wheels the tree would pass the 64 MiB a call carries).
set -u
source scripts/gpu-unpack.sh base
for round in 1 2; do
  for v in base head; do
    [ "$(elapsed)" -lt 480 ] || break
    if [ $v = base ]; then b=rel/base; e="RAYKIN_WAVE_REFILL_GROUPS=4096"; else b=relb/head; e="RAYKIN_UNUSED=1"; fi
    RAYKIN_WAVE_REFILL=on RAYKIN_WAVE_SORT=off frame_rows $v frames.txt $b $e --scene cornell --scene env-lit \
      --scene many-lights --width 960 --height 540 --spp-per-frame 16 --frames 24 --integrator wavefront
    RAYKIN_WAVE_REFILL=on frame_rows $v frames.txt $b $e --scene seed-interior --scene crowd \
      --width 2560 --height 1440 --frames 24 --integrator auto
  done
done
echo "frames: $(elapsed) s" >> "$OUT/frames.txt"
cat "$OUT/gpu.txt" "$OUT/frames.txt"; cat "$OUT/errors.txt" 2>/dev/null; true
