#!/usr/bin/env bash
# Twenty-first session, call 2 (relb/head.xz = bbdf2ad: the kernels without naga's loop bounding and integer-division
# guards). Three parts:
# 1. the Mitsuba 3 side by side (scripts/gpu-mitsuba.sh), all five static scenes, `--integrator auto`, the median of
#    three Mitsuba renders per count (the twentieth session's call 5) -> side-by-side.tgz, summary.md;
# 2. the runtime checks A/B with the form fixed: the bench's frame loop (960x540, 16 spp per frame, 24 frames) over
#    the five scenes, megakernel and wavefront, with the default checks (`fewer`), wgpu's (`all`) and none
#    (`none`, a probe), after one warm-up run, two rounds -> checks.txt;
# 3. FlightHelmet's next-event estimation split: `noshadow` (the light sampled and its contribution added, the
#    shadow ray not traced; RAYKIN_SHADER_DIR) against the head, megakernel, two rounds -> frames.txt.
# Carry [".gl", "relb", ".whl"].
set -u
source scripts/gpu-unpack.sh
export RAYKIN_COMMIT=bbdf2ad
MITSUBA_REPEATS=3 ASSETS=relb/assets RAYKIN_BIN=relb/head RAYKIN_INTEGRATOR=auto \
  timeout 330 bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
echo "side by side: $(elapsed) s"
grep -v warning /tmp/run.log | tail -n 12
bench_rows() {  # label, file, env assignment, bench options...
  local w; w=$(mktemp -d); local label=$1 file=$2 envs=$3; shift 3
  env "$envs" relb/head bench --suite full --parts frames --frames 24 --width 960 --height 540 --spp-per-frame 16 \
    "$@" --assets relb/assets --out "$w" --cache "$w/c" > "$w/log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']: print('$label', row['scene'], row['width'], row['spp_per_frame'], row['trace_ms_median'], row['integrator'])
" >> "$OUT/$file" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
all_scenes=(--scene cornell --scene flight-helmet --scene spheres --scene env-lit --scene many-lights)
bench_rows warm-up /dev/null RAYKIN_NONE=1 "${all_scenes[@]}" --integrator megakernel
for round in 1 2; do
  [ "$(elapsed)" -gt 480 ] && break
  for v in fewer all none; do
    for form in megakernel wavefront; do
      bench_rows "$v" checks.txt RAYKIN_SHADER_CHECKS=$v "${all_scenes[@]}" --integrator $form
    done
  done
done
echo "checks: $(elapsed) s" | tee -a "$OUT/checks.txt"
mkdir -p relb/ablate/noshadow/integrator
sed 's/^            shadow_pending = any(shadow.contribution != vec3<f32>(0.0));$/&\n            if dims != 0xfffffffeu { result.radiance += shadow.contribution; shadow_pending = false; }/' \
  shaders/integrator/path.wgsl > relb/ablate/noshadow/integrator/path.wgsl
grep -c 0xfffffffeu relb/ablate/noshadow/integrator/path.wgsl >> "$OUT/frames.txt"
for round in 1 2; do
  [ "$(elapsed)" -gt 560 ] && break
  bench_rows head frames.txt RAYKIN_NONE=1 --scene flight-helmet --integrator megakernel
  bench_rows noshadow frames.txt RAYKIN_SHADER_DIR=$PWD/relb/ablate/noshadow --scene flight-helmet --integrator megakernel
done
echo "total: $(elapsed) s" | tee -a "$OUT/frames.txt"
cat "$OUT/checks.txt" "$OUT/frames.txt"
