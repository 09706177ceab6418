#!/usr/bin/env bash
# Second of two device calls (the first carried .oidnpack-a and ran `cp .oidnpack-a/oidnpart.00 /root/`, as in
# ../gpu-h200-2026-12-04-split/gains.sh): OIDN's error gains on FlightHelmet and the Cornell box at 960x540 with the
# new bound row (the noisy colour with converged AOVs: 256 spp of another seed, cleanAux), to see whether the AOVs
# are what holds FlightHelmet's 4-spp gain under the 10x. Binary rel/raykin-s.xz = 3cd04b7 at opt-level 3.
set -u
[ -f /root/oidnpart.00 ] || { echo "no /root/oidnpart.00: the machine was not the warm one"; exit 3; }
mkdir -p /root/oidn/lib && cat /root/oidnpart.00 .oidnpack-b/oidnpart.01 | xz -d | tar x -C /root/oidn/lib
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json RAYKIN_OIDN_DIR=/root/oidn/lib
(cd rel && xz -dkf raykin-s.xz && chmod +x raykin-s)
w=$(mktemp -d)
RAYKIN_EXPERIMENT_SCALE=1 timeout 420 rel/raykin-s bench --suite full --parts oidn --scene flight-helmet \
  --assets rel/assets --out "$w" --cache "$w/c" > "$w/gains.log" 2>&1
echo "bench rc $?"
cp "$w/results.json" "$OUT/gains-results.json"; cp "$w/summary.md" "$OUT/gains-summary.md"
grep "4 spp" "$w/gains.log" | cut -c1-220
