#!/usr/bin/env bash
# Twentieth session, call 6, scripted but not run (no machine was lent) (relb/head.xz = 07cae21's code or
# later): where FlightHelmet's megakernel time goes, by ablation (the nineteenth session's "next" item 3), and the
# Cornell box's waves without next-event estimation.
# Variants through RAYKIN_SHADER_DIR (relb/ablate/, made below from the tree's shaders, each an early return behind
# a condition the compiler cannot fold): `notex` (sample_texture returns a constant: no texel reads), `nonee`
# (sample_direct returns no light: no light sampling, no shadow rays); and the head at --max-depth 1, 2, 3.
# Images differ (ablations), only the times mean anything.
# The bench's frame loop, 960x540, 16 spp per frame, 24 frames, two rounds -> frames.txt. Carry [".gl", "relb"].
set -u
source scripts/gpu-unpack.sh
mkdir -p relb/ablate/notex/scene relb/ablate/nonee/integrator
sed 's/^fn sample_texture(texture: u32, uv_in: vec2<f32>) -> vec4<f32> {$/&\n    if texture != 0xfffffffeu { return vec4<f32>(0.5, 0.5, 1.0, 1.0); }/' \
  shaders/scene/texture.wgsl > relb/ablate/notex/scene/texture.wgsl
sed 's/^    let none = no_direct_light();$/&\n    if dims != 0xfffffffeu { return none; }/' \
  shaders/integrator/path.wgsl > relb/ablate/nonee/integrator/path.wgsl
frames() {  # label, shader dir (or -), integrator, bench options...
  local w; w=$(mktemp -d); local label=$1 dir=$2 integrator=$3; shift 3
  local envs=RAYKIN_NONE=1; [ "$dir" != - ] && envs=RAYKIN_SHADER_DIR=$PWD/relb/ablate/$dir
  env "$envs" relb/head bench --suite full --parts frames --frames 24 --integrator "$integrator" "$@" \
    --assets relb/assets --out "$w" --cache "$w/c" > "$w/log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']: print('$label', row['scene'], row['width'], row['spp_per_frame'], row['trace_ms_median'], row['integrator'])
" >> "$OUT/frames.txt" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
small=(--width 960 --height 540 --spp-per-frame 16)
for round in 1 2; do
  [ "$(elapsed)" -gt 300 ] && break
  frames head - megakernel --scene flight-helmet "${small[@]}"
  frames notex notex megakernel --scene flight-helmet "${small[@]}"
  frames nonee nonee megakernel --scene flight-helmet "${small[@]}"
  for d in 1 2 3; do frames "depth-$d" - megakernel --scene flight-helmet "${small[@]}" --max-depth $d; done
  frames head - wavefront --scene cornell "${small[@]}"
  frames nonee nonee wavefront --scene cornell "${small[@]}"
done
echo "total: $(elapsed) s" | tee -a "$OUT/frames.txt"
cat "$OUT/frames.txt"
