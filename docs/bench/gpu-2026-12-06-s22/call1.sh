#!/usr/bin/env bash
# Twenty-second session, call 1. relb/head.xz = c74d310 (the twenty-first session's end), relb/smooth.xz = the
# same with smooth environments left to BSDF sampling (`environment::sampling::SMOOTH_PEAK_TO_MEAN`: the sky
# gradient is no longer sampled by next-event estimation). Parts:
# 1. A/B head vs smooth, the frame loop (960x540, 16 spp per frame, 24 frames, the megakernel and the waves),
#    FlightHelmet and the spheres (the bench's scenes under the sky gradient), alternating, three rounds
#    -> smooth.txt (trace ms; the variance side was measured on lavapipe, docs/BENCHMARKS.md);
# 2. then the twenty-first session's call 3 without its side by side (gpu-2026-12-05-s21/call3.sh: auto's
#    choices, the lazy last vertex, the seed-like interior's checks), its seed part bounded to what is left.
# Made by `bash scripts/gpu-pack.sh` plus relb/smooth.xz; carry [".gl", "relb"].
set -u
source scripts/gpu-unpack.sh
(cd relb && xz -dkf smooth.xz && chmod +x smooth)
ab_rows() {  # label, binary, bench options...
  local w; w=$(mktemp -d); local label=$1 bin=$2; shift 2
  "relb/$bin" bench --suite full --parts frames "$@" --assets relb/assets --out "$w" --cache "$w/c" > "$w/log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']: print('$label', row['scene'], row['width'], row['spp_per_frame'], row['trace_ms_median'], row['integrator'])
" >> "$OUT/smooth.txt" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
for round in 1 2 3; do
  for bin in head smooth; do
    for form in megakernel wavefront; do
      ab_rows "$bin" "$bin" --frames 24 --width 960 --height 540 --spp-per-frame 16 --integrator $form \
        --scene flight-helmet --scene spheres
    done
  done
done
echo "smooth: $(elapsed) s" | tee -a "$OUT/smooth.txt"
cat "$OUT/smooth.txt"
SIDE_BY_SIDE=off SEED_UNTIL=$(( 540 - $(elapsed) )) RAYKIN_COMMIT=c74d310 bash docs/bench/gpu-2026-12-05-s21/call3.sh
