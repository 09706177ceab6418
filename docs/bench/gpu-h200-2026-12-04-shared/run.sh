#!/usr/bin/env bash
# Device call (second of two): OIDN's CUDA device over GPU memory shared with wgpu (raykin::oidn::shared) against
# the host path, same binary, same call: `raykin bench --parts oidn` times both paths (and shared without the
# prefilters) and compares their outputs; one-off renders report which path ran. Binary: 2a2a630, workspace at
# opt-level 3 (`CARGO_PROFILE_DEV_OPT_LEVEL=3 cargo build -p raykin`), stripped, as rel/raykin-s.xz.
# Second run, `run.sh raykin-v` (files *-v.*): c40ccea, built the same way (the viewer's path, the output written
# for display on the GPU, timed and compared too).
# The call before (carry .gl and .oidnpack, nothing else in the tree beyond git's files):
#   mkdir -p /root/oidn/lib && tar xJf .oidnpack/oidn-cuda.tar.xz -C /root/oidn/lib
# where oidn-cuda.tar.xz = libOpenImageDenoise.so.2, libOpenImageDenoise_core.so.2.5.1,
# libOpenImageDenoise_device_cuda.so.2.5.1 and libtbb.so.12 from scripts/setup.sh's .oidn/lib (tar | xz -9e, 47 MB).
set -u
[ -f /root/oidn/lib/libOpenImageDenoise.so.2 ] || { echo "no /root/oidn/lib: the machine was not the warm one"; exit 3; }
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json RAYKIN_OIDN_DIR=/root/oidn/lib
b=${1:-raykin-s}
(cd rel && xz -dkf $b.xz && chmod +x $b)
for size in 1920x1080 2560x1440; do
  for aovs in prefilter clean; do
    rel/$b render rel/assets/CornellBox/CornellBox.glb --spp 4 --width ${size%x*} --height ${size#*x} \
      --denoise oidn --denoise-quality fast --denoise-aovs $aovs --out /tmp/x.png --report /tmp/r.json \
      >> "$OUT/render.log" 2>&1
    python3 -c "
import json; r=json.load(open('/tmp/r.json'))
print('$size', '$aovs', {k: v for k, v in r.items() if 'oidn' in k})" | tee -a "$OUT/renders.txt"
  done
done
w=$(mktemp -d)
timeout 400 rel/$b bench --suite full --parts oidn --scene cornell --assets rel/assets --out "$w" \
  --cache "$w/c" > "$OUT/bench.log" 2>&1
echo "bench rc $?"
cp "$w/results.json" "$OUT/results.json" 2>/dev/null
grep "raykin bench: OIDN" "$OUT/bench.log" | grep -v "CPU" | head -40
