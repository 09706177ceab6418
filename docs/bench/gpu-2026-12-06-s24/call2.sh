#!/usr/bin/env bash
# Twenty-fourth session, call 2. relb/head.xz = 1e14bbe + `--rr-depth` on render and bench. Parts:
# 1. seed: the seed-like interior's frame loop (2560x1440, 1 spp, depth 6, waves, 30 frames) with its traversal
#    counters and ray-casting rates -> seed.txt;
# 2. rr: where Russian roulette pays to start in the forms auto picks now: the error part's 16-spp curve of the five
#    static scenes (960x540, depth 6, `--integrator auto`) with --rr-depth 3, 5 and 4, by rounds until RR_UNTIL
#    (default 560 s) -> rr.txt (rr-depth.py), traced-by.txt.
# Made by `bash scripts/gpu-pack.sh`; carry [".gl", "relb"].
set -u
source scripts/gpu-unpack.sh
scenes=(--scene cornell --scene spheres --scene flight-helmet --scene env-lit --scene many-lights)
seed() {
  relb/head bench --suite full --parts frames --scene seed-interior --width 2560 --height 1440 --integrator wavefront \
    --frames 30 --assets relb/assets --out /tmp/seed --cache /tmp/seed-cache 2>&1 | grep "raykin bench" > "$OUT/seed.txt"
  echo "seed: $(elapsed) s" >> "$OUT/seed.txt"
}
rr() {
  mkdir -p /tmp/rr
  for round in 1 2; do
    for depth in 3 5 4; do
      [ "$(elapsed)" -gt "${RR_UNTIL:-560}" ] && break 2
      timeout $(( ${RR_UNTIL:-560} + 20 - $(elapsed) )) relb/head bench --suite full "${scenes[@]}" \
        --assets relb/assets --parts errors --curve "16 spp" --integrator auto --rr-depth $depth \
        --out /tmp/rr/$round-$depth --cache /tmp/rr-cache > /tmp/rr/$round-$depth.log 2>&1
      grep -h "traced by" /tmp/rr/$round-$depth.log | sed "s/^/$round-$depth /" >> "$OUT/traced-by.txt"
      echo "round $round depth $depth: $(elapsed) s" >> "$OUT/rr.txt"
    done
  done
  python3 docs/bench/gpu-2026-12-06-s24/rr-depth.py /tmp/rr >> "$OUT/rr.txt"
  cat "$OUT/rr.txt"
}
for part in ${PARTS:-seed rr}; do "$part"; done
