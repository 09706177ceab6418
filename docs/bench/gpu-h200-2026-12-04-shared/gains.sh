#!/usr/bin/env bash
# Device call (after the one that unpacks OIDN, as run.sh says): the error-vs-time curves (none, svgf, oidn,
# oidn-fast) and OIDN's relMSE/FLIP gains at 1, 4, 16 and 64 spp on the Cornell box, FlightHelmet and the crowd,
# with OIDN's CUDA device (shared GPU memory). `gains.sh BINARY`: raykin-v = c40ccea (files gains-*.{md,log} and
# error-vs-time-*.png), raykin-u = a446bbe (OIDN denoises only the scattered radiance; files *-u.*), raykin-w =
# 3f7866c (only sky pixels set apart, reverted; files *-w.*), each built as run.sh says. rel/assets holds
# CornellBox, FlightHelmet, CesiumMan and Fox from ../shared/assets.
set -u
[ -f /root/oidn/lib/libOpenImageDenoise.so.2 ] || { echo "no /root/oidn/lib: the machine was not the warm one"; exit 3; }
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json RAYKIN_OIDN_DIR=/root/oidn/lib
b=${1:-raykin-v}
(cd rel && xz -dkf $b.xz && chmod +x $b)
w=$(mktemp -d)
timeout 560 rel/$b bench --suite full --parts errors --parts oidn --scene cornell --scene flight-helmet --scene crowd \
  --assets rel/assets --out "$w" --cache "$w/c" > "$OUT/gains.log" 2>&1
echo "bench rc $?"
cp "$w/results.json" "$OUT/gains-results.json" 2>/dev/null
cp "$w"/summary.md "$OUT/gains-summary.md" 2>/dev/null
ls -R "$w" | head -30
cp "$w"/charts/error-vs-time*.png "$OUT/" 2>/dev/null
tail -5 "$OUT/gains.log"
