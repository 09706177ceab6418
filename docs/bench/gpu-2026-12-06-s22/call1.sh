#!/usr/bin/env bash
# Twenty-second session, call 1. relb/bins.tar.xz holds two stripped release binaries (one archive: xz's 64 MiB
# window stores the second nearly for free, and both with Mitsuba's wheels fit the call's 64 MiB): `head` =
# c74d310 (the twenty-first session's end), `smooth` = RAYKIN_COMMIT (f31f912 in the twenty-third session's run:
# 1d84f06's smooth environments left to BSDF sampling, `environment::sampling::SMOOTH_PEAK_TO_MEAN`, the sky
# gradient no longer sampled by next-event estimation; b729225's light-kind gate acts on CPU adapters only).
# Parts:
# 1. the Mitsuba 3 side by side of smooth (scripts/gpu-mitsuba.sh) on the bench's two scenes under the sky gradient
#    (FlightHelmet, the spheres; the other three have no smooth map), `--integrator auto` (its trials printed
#    beside each curve -> traced-by.txt), the median of three Mitsuba renders per count, at most
#    SIDE_BY_SIDE_SECONDS (default 200) -> side-by-side.tgz, summary.md;
# 2. A/B head vs smooth, the frame loop (960x540, 16 spp per frame, 24 frames, the megakernel and the waves),
#    the same two scenes, alternating, two rounds, until CALL_UNTIL s (default 270) -> smooth.txt (trace ms;
#    the variance side was measured on lavapipe).
# PARTS (default "side_by_side a_b") sets the order; SIDE_BY_SIDE_SCENES, AB_ROUNDS and AB_FORMS
# narrow them.
# Made by `bash scripts/gpu-pack.sh --mitsuba` on each commit (its relb/head.xz unpacked and renamed), then
# `tar cf - head smooth | xz -9 > relb/bins.tar.xz`, the .xz files removed and only the assets of FlightHelmet and
# the spheres kept (CornellBox too for a five-scene side by side); carry [".gl", "relb", ".whl"]. Written in the
# twenty-second session (no device machine could be started), run in the twenty-third.
set -u
source scripts/gpu-unpack.sh
tar -C relb -xJf relb/bins.tar.xz
side_by_side() {
  MITSUBA_SCENES="${SIDE_BY_SIDE_SCENES:-flight-helmet spheres}" MITSUBA_REPEATS=3 ASSETS=relb/assets \
    RAYKIN_BIN=relb/smooth RAYKIN_INTEGRATOR=auto RAYKIN_COMMIT="${RAYKIN_COMMIT:-f31f912}" \
    timeout "${SIDE_BY_SIDE_SECONDS:-200}" \
    bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
  echo "side by side: $(elapsed) s"
  grep -h "traced by" /tmp/gpu-mitsuba/bench.log > "$OUT/traced-by.txt"
  tail -8 "$OUT/summary.md"
}
a_b() {
  for round in $(seq "${AB_ROUNDS:-2}"); do
    for bin in head smooth; do
      for form in ${AB_FORMS:-megakernel wavefront}; do
        [ "$(elapsed)" -gt "${CALL_UNTIL:-270}" ] && break 3
        frame_rows "$bin" smooth.txt "relb/$bin" RAYKIN_NONE=1 --frames 24 --width 960 --height 540 \
          --spp-per-frame 16 --integrator $form --scene flight-helmet --scene spheres
      done
    done
  done
  echo "smooth: $(elapsed) s" | tee -a "$OUT/smooth.txt"
  cat "$OUT/smooth.txt"
}
for part in ${PARTS:-side_by_side a_b}; do "$part"; done
