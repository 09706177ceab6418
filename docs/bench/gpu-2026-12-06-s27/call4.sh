#!/usr/bin/env bash
# Twenty-seventh session, call 4. rel/paths.xz = the path rays sorted (extend reading a sorted copy of the queue,
# shade the queue) with auto's sort trial; relb/head.xz = the same with the shadow rays sorted too (their keys
# after the paths', extend reading both in the sort's order).
# 1. The seed-like interior and the crowd at 2560x1440, 1 spp, depth 6, waves fixed: unsorted, paths sorted,
#    paths and shadows sorted (`RAYKIN_WAVE_SORT` forcing it), two rounds -> forced.txt.
# 2. `--integrator auto` with the sort's trial (head) against the sort off: the seed, the crowd, and the static
#    scenes auto traces in waves (env-lit, many-lights) and the Cornell box at 960x540, 16 spp a frame (the
#    device time left was short: the crowd's second round and the other static scenes left out) -> auto.txt (label, scene, width, trace ms median, frame ms median, form,
#    rays sorted, auto's forms trial [megakernel, waves] ms, the sort's trial [unsorted, sorted] ms).
# Carry [".gl", "relb", "rel"].
set -u
source scripts/gpu-unpack.sh paths
rows() {
  local w; w=$(mktemp -d); local file=$1 label=$2 bin=$3 envs=$4 scene=$5; shift 5
  env $envs $bin bench --suite full --parts frames --scene "$scene" "$@" \
    --frames 24 --assets relb/assets --out "$w" --cache "$w/c" > "$w/log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']:
    print('$label', row['scene'], row['width'], round(row['trace_ms_median'],3), round(row['frame_ms']['median'],3), row['integrator'], row.get('rays_sorted'), str(row.get('auto_trial_ms')).replace(' ',''), str(row.get('sort_trial_ms')).replace(' ',''))
" >> "$OUT/$file" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
for round in 1 2; do
  scenes="seed-interior crowd"; [ $round = 2 ] && scenes=seed-interior
  for scene in $scenes; do
    rows forced.txt unsorted relb/head RAYKIN_WAVE_SORT=off $scene --width 2560 --height 1440 --integrator wavefront
    rows forced.txt paths rel/paths RAYKIN_WAVE_SORT=on $scene --width 2560 --height 1440 --integrator wavefront
    rows forced.txt paths+shadows relb/head RAYKIN_WAVE_SORT=on $scene --width 2560 --height 1440 --integrator wavefront
  done
done
echo "forced: $(elapsed) s" >> "$OUT/forced.txt"
for round in 1 2; do
  for scene in seed-interior crowd; do
    rows auto.txt sort-off relb/head RAYKIN_WAVE_SORT=off $scene --width 2560 --height 1440 --integrator auto
    rows auto.txt trial relb/head RAYKIN_X=1 $scene --width 2560 --height 1440 --integrator auto
  done
  for scene in env-lit many-lights cornell; do
    rows auto.txt sort-off relb/head RAYKIN_WAVE_SORT=off $scene --width 960 --height 540 --spp-per-frame 16 --integrator auto
    rows auto.txt trial relb/head RAYKIN_X=1 $scene --width 960 --height 540 --spp-per-frame 16 --integrator auto
  done
  echo "round $round: $(elapsed) s" >> "$OUT/auto.txt"
  [ "$(elapsed)" -gt 120 ] && break
done
cat "$OUT/gpu.txt" "$OUT/forced.txt" "$OUT/auto.txt"; cat "$OUT/errors.txt" 2>/dev/null
