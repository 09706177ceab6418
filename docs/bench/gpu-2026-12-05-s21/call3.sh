#!/usr/bin/env bash
# Twenty-first session, call 3, scripted but not run (no machine could be started; the device time ran out).
# relb/head.xz = 2b2cad0 or later (0e7c148 also prints auto's trials beside each curve): the kernels without
# naga's loop bounding and integer-division guards, and auto's trial decided by each form's fastest frame, re-run
# while unsteady for half a second. Parts,
# run in the order 2, 3, 1, 4 (the quick ones first: less device time was left than planned):
# 1. the Mitsuba 3 side by side (scripts/gpu-mitsuba.sh), all five static scenes, `--integrator auto`, the median of
#    three Mitsuba renders per count -> side-by-side.tgz, summary.md;
# 2. the frame loop with auto (960x540, 16 spp per frame, 24 frames), the five scenes: the forms the trial chose
#    and its times -> frames.txt;
# 3. the waves' last vertex read only where an emitter is hit (relb/lazy/wavefront.wgsl, made below, through
#    RAYKIN_SHADER_DIR)
#    against the head, the frame loop as in 2 with `--integrator wavefront`, two rounds -> lazy.txt;
# 4. the seed-like interior (2560x1440, 1 spp, 30 frames, auto and the megakernel) with the default checks
#    and with wgpu's (`RAYKIN_SHADER_CHECKS=all`), alternating, two rounds -> seed.txt.
# SIDE_BY_SIDE=off skips part 1, SEED_UNTIL (s, default 520) bounds part 4. Made by `bash scripts/gpu-pack.sh
# --mitsuba`; carry [".gl", "relb", ".whl"].
set -u
source scripts/gpu-unpack.sh
export RAYKIN_COMMIT=${RAYKIN_COMMIT:-c74d310}
frame_rows auto frames.txt relb/head RAYKIN_NONE=1 --frames 24 --width 960 --height 540 --spp-per-frame 16 \
  --scene cornell --scene flight-helmet --scene spheres --scene env-lit --scene many-lights
echo "frames: $(elapsed) s" | tee -a "$OUT/frames.txt"
mkdir -p relb/lazy
sed -e 's/^    let vertex = LightSampleContext(path_vertex\[path\].xyz, path_normal\[path\].xyz);$/    let vertex = LightSampleContext(vec3<f32>(0.0), vec3<f32>(0.0));/' \
  -e 's/direct_pdf_of_hit(hit, s.p, p.last_vertex, p.ray.dir)/direct_pdf_of_hit(hit, s.p, LightSampleContext(path_vertex[path].xyz, path_normal[path].xyz), p.ray.dir)/' \
  engine/src/render/passes/wavefront/wavefront.wgsl > relb/lazy/wavefront.wgsl
grep -c "LightSampleContext(path_vertex" relb/lazy/wavefront.wgsl >> "$OUT/lazy.txt"
for round in 1 2; do
  [ "${LAZY:-on}" = on ] || break
  for v in head lazy; do
    envs=RAYKIN_NONE=1; [ $v = lazy ] && envs=RAYKIN_SHADER_DIR=$PWD/relb/lazy
    frame_rows $v lazy.txt relb/head "$envs" --frames 24 --width 960 --height 540 --spp-per-frame 16 \
      --integrator wavefront --scene cornell --scene spheres --scene env-lit --scene many-lights
  done
done
echo "lazy: $(elapsed) s" | tee -a "$OUT/lazy.txt"
if [ "${SIDE_BY_SIDE:-on}" = on ]; then
  MITSUBA_REPEATS=3 ASSETS=relb/assets RAYKIN_BIN=relb/head RAYKIN_INTEGRATOR=auto \
    timeout "${SIDE_BY_SIDE_SECONDS:-330}" bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
  echo "side by side: $(elapsed) s"
  grep -h "traced by" /tmp/gpu-mitsuba/bench.log > "$OUT/traced-by.txt"
fi
for round in 1 2; do
  for v in fewer all; do
    [ "$(elapsed)" -gt "${SEED_UNTIL:-520}" ] && break 2
    seed=(--frames 30 --scene seed-interior --width 2560 --height 1440)
    frame_rows "$v" seed.txt relb/head RAYKIN_SHADER_CHECKS=$v "${seed[@]}"
    frame_rows "$v" seed.txt relb/head RAYKIN_SHADER_CHECKS=$v "${seed[@]}" --integrator megakernel
  done
done
echo "total: $(elapsed) s" | tee -a "$OUT/seed.txt"
cat "$OUT/frames.txt" "$OUT/lazy.txt" "$OUT/seed.txt"
