#!/usr/bin/env bash
# Twenty-third session, call 2. relb/head.xz = the specialised kernels (gpu/specialize.rs: each pipeline's
# constants substituted and the branches they decide removed before wgpu sees it; RAYKIN_SPECIALIZE=off hands
# wgpu the WGSL and the constants as before). Parts:
# 1. start-up: `render` of the Cornell box and FlightHelmet at 64x64, 1 spp, the NVIDIA driver's shader disk cache
#    off (__GL_SHADER_DISK_CACHE=0), wall seconds and the path tracer's compile ms, off / on, three rounds
#    -> startup.txt;
# 2. the frame loop (960x540, 16 spp a frame, 24 frames), off / on alternating, the five static scenes, the
#    megakernel and the waves, two rounds; the seed-like interior (2560x1440, 1 spp, depth 6, 30 frames, waves)
#    -> spec.txt;
# 3. the Cornell box's megakernel with path regeneration (RAYKIN_PATH_REGENERATION=on, the CPU adapters' form)
#    against the megakernel and the waves -> cornell.txt;
# 4. the Mitsuba 3 side by side of the five static scenes (`--integrator auto`, the median of three Mitsuba renders
#    per count), until CALL_UNTIL (default 560 s) -> side-by-side.tgz, summary.md, traced-by.txt.
# Made by `bash scripts/gpu-pack.sh --mitsuba`; carry [".gl", "relb", ".whl"]. Ran with RAYKIN_COMMIT=fdbe394 (as
# run, the warm-up's rows went to $OUT//dev/null, which failed, so its log's tail went to errors.txt: harmless).
set -u
source scripts/gpu-unpack.sh
export RAYKIN_COMMIT=${RAYKIN_COMMIT:-unknown}
scenes=(--scene cornell --scene spheres --scene flight-helmet --scene env-lit --scene many-lights)
startup() {
  for round in 1 2 3; do
    for v in off on; do
      for scene in CornellBox/CornellBox.glb FlightHelmet/glTF/FlightHelmet.gltf; do
        local s0; s0=$(date +%s.%N)
        local ms; ms=$(__GL_SHADER_DISK_CACHE=0 RAYKIN_SPECIALIZE=$v RUST_LOG=raykin=debug,wgpu=warn,naga=warn \
          relb/head render "relb/assets/$scene" --width 64 --height 64 --spp 1 --out /tmp/s.exr 2>&1 \
          | grep "path trace" | sed 's/.*compiled in //')
        echo "$v $round ${scene%%/*} wall $(python3 -c "import time; print(f'{time.time() - $s0:.3f}')") s, trace pipeline $ms" \
          >> "$OUT/startup.txt"
      done
    done
  done
  cat "$OUT/startup.txt"
}
frames() {
  frame_rows warm-up /dev/null relb/head RAYKIN_NONE=1 "${scenes[@]}" --frames 8 --width 960 --height 540 \
    --spp-per-frame 16 --integrator megakernel
  for round in 1 2; do
    for v in off on; do
      for form in megakernel wavefront; do
        [ "$(elapsed)" -gt 300 ] && break 3
        frame_rows "$v" spec.txt relb/head RAYKIN_SPECIALIZE=$v "${scenes[@]}" --frames 24 --width 960 --height 540 \
          --spp-per-frame 16 --integrator $form
      done
    done
  done
  for v in off on; do
    frame_rows "$v" spec.txt relb/head RAYKIN_SPECIALIZE=$v --scene seed-interior --frames 30 --width 2560 \
      --height 1440 --integrator wavefront
  done
  echo "frames: $(elapsed) s" | tee -a "$OUT/spec.txt"
  cat "$OUT/spec.txt"
}
cornell() {
  for round in 1 2; do
    for v in regeneration megakernel wavefront; do
      local form=$v envs=RAYKIN_NONE=1
      [ $v = regeneration ] && form=megakernel envs=RAYKIN_PATH_REGENERATION=on
      frame_rows "$v" cornell.txt relb/head $envs --scene cornell --frames 24 --width 960 --height 540 \
        --spp-per-frame 16 --integrator $form
    done
  done
  echo "cornell: $(elapsed) s" | tee -a "$OUT/cornell.txt"
  cat "$OUT/cornell.txt"
}
side_by_side() {
  local left=$(( ${CALL_UNTIL:-560} - $(elapsed) ))
  [ "$left" -lt 120 ] && { echo "no time left for the side by side"; return; }
  MITSUBA_REPEATS=3 ASSETS=relb/assets RAYKIN_BIN=relb/head RAYKIN_INTEGRATOR=auto timeout "$left" \
    bash scripts/gpu-mitsuba.sh "$OUT" > /tmp/run.log 2>&1
  echo "side by side: $(elapsed) s"
  grep -h "traced by" /tmp/gpu-mitsuba/bench.log > "$OUT/traced-by.txt"
  tail -9 "$OUT/summary.md"
}
# Added for the rerun with e7d3ce2 (PARTS="images startup frames"): whether the specialised kernels give the same
# image on the GPU, byte for byte (128x128, 16 spp) -> images.txt.
images() {
  for scene in CornellBox/CornellBox.glb FlightHelmet/glTF/FlightHelmet.gltf \
    MetalRoughSpheresNoTextures/glTF/MetalRoughSpheresNoTextures.gltf; do
    for v in off on; do
      RAYKIN_SPECIALIZE=$v relb/head render "relb/assets/$scene" --width 128 --height 128 --spp 16 \
        --out "/tmp/image-$v.exr" > /dev/null 2>&1
    done
    if cmp -s /tmp/image-off.exr /tmp/image-on.exr; then r=identical; else r=differ; fi
    echo "${scene%%/*}: $r" | tee -a "$OUT/images.txt"
  done
}
for part in ${PARTS:-startup frames cornell side_by_side}; do "$part"; done
