#!/usr/bin/env bash
# Device call (second of two): Open Image Denoise's CUDA device with the one-staging-buffer readback (binary
# 45cb732 as rel/raykin-a.xz). OIDN's libraries (libOpenImageDenoise, its core, the CUDA device and TBB from the
# pyoidn 2.5.1 wheel) do not fit the 64 MiB carry beside the binary and the tree, so the call before this one
# carried them alone and unpacked them to /root/oidn/lib (the folder must be called lib: the libraries' RPATH is
# $ORIGIN/../lib), which lives on while the machine stays warm.
# The call before (carry .gl and .oidnpack, nothing else in the tree beyond git's files):
#   mkdir -p /root/oidn/lib && tar xJf .oidnpack/oidn-cuda.tar.xz -C /root/oidn/lib
# where oidn-cuda.tar.xz = libOpenImageDenoise.so.2, libOpenImageDenoise_core.so.2.5.1,
# libOpenImageDenoise_device_cuda.so.2.5.1 and libtbb.so.12 from scripts/setup.sh's .oidn/lib (tar | xz -9e, 47 MB).
set -u
[ -f /root/oidn/lib/libOpenImageDenoise.so.2 ] || { echo "no /root/oidn/lib: the machine was not the warm one"; exit 3; }
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json RAYKIN_OIDN_DIR=/root/oidn/lib
(cd rel && xz -dkf raykin-a.xz && chmod +x raykin-a)
w=$(mktemp -d)
timeout 300 rel/raykin-a bench --suite full --parts oidn --scene cornell --assets rel/assets --out "$w" \
  --cache "$w/c" > "$OUT/bench.log" 2>&1
cp "$w/results.json" "$OUT/bench-results.json" 2>/dev/null
for size in 1920x1080 2560x1440; do
  for q in high fast; do
    for aovs in prefilter clean; do
      for run in 1 2; do
        rel/raykin-a render rel/assets/CornellBox/CornellBox.glb --spp 4 --width ${size%x*} --height ${size#*x} \
          --denoise oidn --denoise-quality $q --denoise-aovs $aovs --out /tmp/x.png --report /tmp/r.json \
          >> "$OUT/render.log" 2>&1
        python3 -c "
import json; r=json.load(open('/tmp/r.json'))
print('$size', '$q', '$aovs', $run, {k: v for k, v in r.items() if 'oidn' in k or 'denois' in k})" | tee -a "$OUT/renders.txt"
      done
    done
  done
done
