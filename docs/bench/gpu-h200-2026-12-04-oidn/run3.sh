#!/usr/bin/env bash
# Device call (second of two, as run.sh): OIDN's buffers in host storage. raykin-c: as in run2.sh (staging buffer
# kept, parallel means); raykin-d: c with OIDN's images in host-storage buffers (pinned host memory the CUDA
# device reads and writes), sanitised into them in place in parallel and the output read from them, instead of
# device buffers filled and read through oidnWriteBuffer/oidnReadBuffer. Both at opt-level 3 (see run2.sh).
# The call before (carry .gl and .oidnpack, nothing else in the tree beyond git's files):
#   mkdir -p /root/oidn/lib && tar xJf .oidnpack/oidn-cuda.tar.xz -C /root/oidn/lib
# where oidn-cuda.tar.xz = libOpenImageDenoise.so.2, libOpenImageDenoise_core.so.2.5.1,
# libOpenImageDenoise_device_cuda.so.2.5.1 and libtbb.so.12 from scripts/setup.sh's .oidn/lib (tar | xz -9e, 47 MB).
set -u
[ -f /root/oidn/lib/libOpenImageDenoise.so.2 ] || { echo "no /root/oidn/lib: the machine was not the warm one"; exit 3; }
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json RAYKIN_OIDN_DIR=/root/oidn/lib
export RUST_LOG=raykin::gpu=debug
(cd rel && for b in raykin-c raykin-d; do xz -dkf $b.xz && chmod +x $b; done)
for b in raykin-c raykin-d; do
  w=$(mktemp -d)
  timeout 200 rel/$b bench --suite full --parts oidn --scene cornell --assets rel/assets --out "$w" \
    --cache "$w/c" > "$OUT/bench-$b.log" 2>&1
  cp "$w/results.json" "$OUT/results-$b.json" 2>/dev/null
done
for size in 1920x1080 2560x1440; do
  for run in 1 2; do
    for b in raykin-c raykin-d; do
      rel/$b render rel/assets/CornellBox/CornellBox.glb --spp 4 --width ${size%x*} --height ${size#*x} \
        --denoise oidn --denoise-quality fast --out /tmp/x.png --report /tmp/r.json >> "$OUT/render.log" 2>&1
      python3 -c "
import json; r=json.load(open('/tmp/r.json'))
print('$b', '$size', $run, {k: v for k, v in r.items() if 'oidn' in k})" | tee -a "$OUT/renders.txt"
    done
  done
done
