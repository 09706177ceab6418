#!/usr/bin/env bash
# Second of two device calls: OIDN's error gains (`raykin bench --parts oidn`: relMSE/FLIP at 1, 4, 16, 64 spp,
# 960x540, against 4096-spp references) on FlightHelmet, the Cornell box and the crowd with the pixel split of
# oidn::inputs::PixelSplit (binary rel/raykin-z.xz: the tree of this commit, opt-level 3, stripped; rel/assets
# holds CornellBox, FlightHelmet, CesiumMan and Fox). The renders are deterministic, so the error figures compare
# with the earlier runs' (docs/bench/gpu-h200-2026-12-04-shared/gains-summary-u.md, the split before this one).
# OIDN's CUDA libraries (scripts/setup.sh's .oidn/lib packed as in ../gpu-h200-2026-12-04-shared/run.sh, 47 MB)
# do not fit beside the repository in one call's 64 MiB: cut in two with `split -b 24000000`, the first call
# (carry .oidnpack-a) ran `cp .oidnpack-a/oidnpart.00 /root/`, this one carries .gl, .oidnpack-b and rel.
set -u
[ -f /root/oidnpart.00 ] || { echo "no /root/oidnpart.00: the machine was not the warm one"; exit 3; }
mkdir -p /root/oidn/lib && cat /root/oidnpart.00 .oidnpack-b/oidnpart.01 | xz -d | tar x -C /root/oidn/lib
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json RAYKIN_OIDN_DIR=/root/oidn/lib
(cd rel && xz -dkf raykin-z.xz && chmod +x raykin-z)
w=$(mktemp -d)
timeout 480 rel/raykin-z bench --suite full --parts oidn --scene flight-helmet --scene cornell --scene crowd \
  --assets rel/assets --out "$w" --cache "$w/c" > "$w/gains.log" 2>&1
echo "bench rc $?"
cp "$w/results.json" "$OUT/gains-results.json"; cp "$w/summary.md" "$OUT/gains-summary.md"
grep -v "warning" "$w/gains.log" | tail -n 40 > "$OUT/gains-log-tail.txt"
grep "oidn high" "$OUT/gains-summary.md"
