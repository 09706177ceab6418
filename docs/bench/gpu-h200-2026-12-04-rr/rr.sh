#!/usr/bin/env bash
# Device call: Russian roulette variants as error-vs-time curves (bench --curve RR: the default, from depth 2 or 5,
# survival threshold 0.5 or 0.25, throughput relative to the first bounce's, that from depth 2) on the five static
# bench scenes, then FlightHelmet's frame loop with and without texture work (a RAYKIN_SHADER_DIR probe whose
# sample_texture returns a constant: rel/var/notex/scene/texture.wgsl is shaders/scene/texture.wgsl with
# notex-texture.patch applied), alternating.
# `rr.sh BINARY`: rel/BINARY.xz is 94c7a94 with rr-variants.patch, opt-level 3, stripped; rel/assets as in the
# other scripts; results under $OUT. The first call ran the five scenes in one bench to 1024 spp and ran out of
# time (its texture rows are call1/textures.txt); the second (call2/) set SKIP_TEXTURES=1.
set -u
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
b=${1:-raykin-rr}
(cd rel && xz -dkf $b.xz && chmod +x $b)
w=$(mktemp -d)
# One invocation per scene (the bench writes its results at the end), curves to 256 spp.
for s in cornell spheres flight-helmet env-lit many-lights; do
  timeout 95 rel/$b bench --suite full --parts errors --curve RR --scene $s --error-max-spp 256 \
    --assets rel/assets --out "$w/rr-$s" --cache "$w/c" > "$w/rr-$s.log" 2>&1
  echo "$s errors rc $?"; tail -2 "$w/rr-$s.log"
  cp "$w/rr-$s/results.json" "$OUT/rr-$s.json"
done
[ -n "${SKIP_TEXTURES:-}" ] && exit 0
for round in 1 2; do
  for v in tex notex; do
    if [ $v = notex ]; then export RAYKIN_SHADER_DIR=rel/var/notex; else unset RAYKIN_SHADER_DIR; fi
    timeout 60 rel/$b bench --suite full --parts frames --frames 60 --spp-per-frame 16 --scene flight-helmet \
      --assets rel/assets --out "$w/$v-$round" --cache "$w/c" > "$w/$v-$round.log" 2>&1
    echo "$v round $round: $(grep '^| flight' "$w/$v-$round/summary.md" | head -1)" | tee -a "$OUT/textures.txt"
  done
done
