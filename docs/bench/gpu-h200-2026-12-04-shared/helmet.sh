#!/usr/bin/env bash
# Device call (after the one that unpacks OIDN, as run.sh says): why OIDN's FLIP on FlightHelmet is worse than
# the noisy image's (gains-summary.md). The bench's FlightHelmet view at 960x540 rendered to PNG: a 4096-spp
# reference, 4 and 64 spp noisy, and OIDN high over the same samples with prefiltered, clean and noisy AOVs.
set -u
[ -f /root/oidn/lib/libOpenImageDenoise.so.2 ] || { echo "no /root/oidn/lib: the machine was not the warm one"; exit 3; }
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json RAYKIN_OIDN_DIR=/root/oidn/lib
b=raykin-v
(cd rel && xz -dkf $b.xz && chmod +x $b)
r() { rel/$b render rel/assets/FlightHelmet/glTF/FlightHelmet.gltf --width 960 --height 540 \
  --look-from -0.0204,0.4244,1.1720 --look-at -0.0204,0.3580,0.0142 --fov 45 --sky "$@" 2>&1 | tail -1; }
r --spp 4096 --out "$OUT/ref.png"
for spp in 4 64; do
  r --spp $spp --out "$OUT/n$spp.png"
  r --spp $spp --denoise oidn --denoise-aovs prefilter --out "$OUT/p$spp.png"
done
r --spp 64 --denoise oidn --denoise-aovs clean --out "$OUT/c64.png"
r --spp 64 --denoise oidn --denoise-aovs noisy --out "$OUT/a64.png"
