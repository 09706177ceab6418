#!/usr/bin/env bash
# Device call 1 (H200): (1) the GPU's clocks during the error part's curves on the Cornell box, the bench of
# a705207 (FLIP between checkpoints: raykin-c) against this commit's (errors after the run: raykin-new), with
# nvidia-smi sampling every 50 ms; (2) trace time of path regeneration, same binary, three kernels alternating:
# sh-a = c4aef18's path loop and sample loop, sh-b = the resumable path (path_advance) in the old sample loop,
# built-in = path regeneration; at 16 spp per frame and at 1. Carry .gl, rel and ab-shaders (made with `git show
# c4aef18:shaders/integrator/path.wgsl` and `...:engine/src/render/passes/trace/trace.wgsl` into ab-shaders/sh-a/
# integrator/path.wgsl and sh-a/trace.wgsl; sh-b: c4aef18 with regeneration.patch's path.wgsl and sh-a's trace.wgsl;
# the binary: c4aef18 with the whole patch (regeneration was not kept, so the patch is its only record).
set -u
OUT=${OUT:-gpu-out}; mkdir -p "$OUT"
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
(cd rel && for b in raykin-c raykin-new; do xz -dkf $b.xz && chmod +x $b; done)
nvidia-smi --query-gpu=timestamp,clocks.sm,clocks.mem,power.draw,pstate,utilization.gpu --format=csv -lms 50 > "$OUT/clocks.csv" 2>&1 &
smi=$!
for b in raykin-c raykin-new; do
  echo "$b start $(date -u +%H:%M:%S.%N)" >> "$OUT/marks.txt"
  rel/$b bench --suite full --parts errors --scene cornell --curve "16 spp" --assets shared/assets \
    --out "$OUT/err-$b" --cache "/tmp/cache-$b" > "$OUT/err-$b.log" 2>&1
  echo "$b end $(date -u +%H:%M:%S.%N)" >> "$OUT/marks.txt"
done
kill $smi
for b in raykin-c raykin-new; do
  python3 - "$OUT/err-$b/results.json" $b <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
for e in r.get('error_vs_time', []):
    for c in e['curves']:
        p = c['points']
        seg = [round((b['time_ms'] - a['time_ms']) / (b['spp'] - a['spp']), 3) for a, b in zip(p, p[1:])]
        print(sys.argv[2], e['scene'], c['name'][:24], 'ms/spp per segment', seg)
PY
done
export SCENES="cornell flight-helmet spheres env-lit many-lights"
OUT="$OUT/ab16" FRAMES=20 BENCH_ARGS="--spp-per-frame 16 --width 1920 --height 1080" \
  bash scripts/gpu-ab-frames.sh 2 raykin-new:ab-shaders/sh-a raykin-new:ab-shaders/sh-b raykin-new
OUT="$OUT/ab1" BENCH_ARGS="--width 1920 --height 1080" \
  bash scripts/gpu-ab-frames.sh 2 raykin-new:ab-shaders/sh-a raykin-new:ab-shaders/sh-b raykin-new
rm -f "$OUT"/err-*/cache -r
tar -C "$OUT" -cJf "$OUT/run1.tar.xz" --exclude run1.tar.xz .
