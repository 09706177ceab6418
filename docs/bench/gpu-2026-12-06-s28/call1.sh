#!/usr/bin/env bash
# Twenty-eighth session, call 1 (the twenty-seventh's call 4, which got no machine, plus the Cornell box's side by
# side where the card is an H200).
# rel/paths.xz = c08b4cf (the path rays sorted, extend reading a sorted copy of the queue; auto's sort trial);
# relb/head.xz = c08b4cf + docs/bench/gpu-2026-12-06-s27/sort-shadows.patch (the shadow rays sorted too).
# 0. On an H200 only: the Cornell box's Mitsuba side by side (auto; the box is traced by the megakernel, which the
#    patch does not touch) -> summary.md, traced-by.txt.
# 1. The seed-like interior and the crowd at 2560x1440, 1 spp, depth 6, waves fixed: unsorted, paths sorted,
#    paths and shadows sorted (`RAYKIN_WAVE_SORT` forcing it); the seed twice -> forced.txt.
# 2. `--integrator auto` with the sort's trial (head) against the sort forced off: the seed-like interior, the
#    crowd, env-lit and the Cornell box (960x540, 16 spp a frame) -> auto.txt (label, scene, width, trace ms
#    median, frame ms median, form, rays sorted, auto's forms trial [megakernel, waves] ms, the sort's trial
#    [unsorted, sorted] ms).
# Made by `bash scripts/gpu-pack.sh --mitsuba` with the patch applied; carry [".gl", "relb", "rel", ".whl"].
set -u
source scripts/gpu-unpack.sh paths
if grep -q H200 "$OUT/gpu.txt"; then
  MITSUBA_SCENES=cornell MITSUBA_REPEATS=3 ASSETS=relb/assets RAYKIN_BIN=relb/head RAYKIN_INTEGRATOR=auto \
    timeout 240 bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
  grep -h "traced by" /tmp/gpu-mitsuba/bench.log > "$OUT/traced-by.txt"
  echo "side by side: $(elapsed) s" >> "$OUT/traced-by.txt"
fi
rows() {
  local w; w=$(mktemp -d); local file=$1 label=$2 bin=$3 envs=$4 scene=$5; shift 5
  [ "$(elapsed)" -lt 560 ] || return
  env $envs timeout 60 $bin bench --suite full --parts frames --scene "$scene" "$@" \
    --frames 24 --assets relb/assets --out "$w" --cache "$w/c" > "$w/log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']:
    print('$label', row['scene'], row['width'], round(row['trace_ms_median'],3), round(row['frame_ms']['median'],3), row['integrator'], row.get('rays_sorted'), str(row.get('auto_trial_ms')).replace(' ',''), str(row.get('sort_trial_ms')).replace(' ',''))
" >> "$OUT/$file" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
for scene in seed-interior crowd seed-interior; do
  rows forced.txt unsorted relb/head RAYKIN_WAVE_SORT=off $scene --width 2560 --height 1440 --integrator wavefront
  rows forced.txt paths rel/paths RAYKIN_WAVE_SORT=on $scene --width 2560 --height 1440 --integrator wavefront
  rows forced.txt paths+shadows relb/head RAYKIN_WAVE_SORT=on $scene --width 2560 --height 1440 --integrator wavefront
done
echo "forced: $(elapsed) s" >> "$OUT/forced.txt"
for scene in seed-interior crowd; do
  rows auto.txt sort-off relb/head RAYKIN_WAVE_SORT=off $scene --width 2560 --height 1440 --integrator auto
  rows auto.txt trial relb/head RAYKIN_X=1 $scene --width 2560 --height 1440 --integrator auto
done
for scene in env-lit cornell; do
  rows auto.txt sort-off relb/head RAYKIN_WAVE_SORT=off $scene --width 960 --height 540 --spp-per-frame 16 --integrator auto
  rows auto.txt trial relb/head RAYKIN_X=1 $scene --width 960 --height 540 --spp-per-frame 16 --integrator auto
done
echo "auto: $(elapsed) s" >> "$OUT/auto.txt"
cat "$OUT/gpu.txt" "$OUT/forced.txt" "$OUT/auto.txt"; cat "$OUT/errors.txt" 2>/dev/null
grep -A12 "### Mitsuba" "$OUT/summary.md" 2>/dev/null
