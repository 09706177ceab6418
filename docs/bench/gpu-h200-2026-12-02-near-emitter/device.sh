#!/usr/bin/env bash
# Device call: the shipped box's expected-error rate (long run) and the CI statistic's spread over seed sets.
set -u
for f in .gl/*.deb; do dpkg -x $f / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
(cd rel && xz -dkf enginetest.xz && chmod +x enginetest)
mkdir -p /work && ln -sfn "$PWD" /work/main
T="$PWD/rel/enginetest"
cd engine
run() { "$T" --exact near_emitter::expected_error_of_the_shipped_box --nocapture 2>&1 | grep -E "^near_emitter|panicked|error" ; }
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
start=$(date +%s)
echo "== long"; RAYKIN_NEAR_RUNS=256 RAYKIN_NEAR_SIZE=64 RAYKIN_NEAR_SPP=4,16,64,256,1024 RAYKIN_NEAR_TOLERANCE=1 run | tee "$OUT/long.txt"
echo "t=$(( $(date +%s) - start ))"
for cfg in "32 16 8,16,32,64,128" "32 16 4,8,16,32,64" "32 32 4,8,16,32,64" "16 32 8,16,32,64,128" "64 8 8,16,32,64,128" "32 16 16,32,64,128,256"; do
  set -- $cfg
  echo "== size $1 runs $2 spp $3"
  RAYKIN_NEAR_SIZE=$1 RAYKIN_NEAR_RUNS=$2 RAYKIN_NEAR_SPP=$3 RAYKIN_NEAR_SEED_SETS=32 RAYKIN_NEAR_TOLERANCE=1 run > "$OUT/sweep-$1-$2-${3//,/_}.txt"
  grep -o "slope [-0-9.]*" "$OUT/sweep-$1-$2-${3//,/_}.txt" | awk '{print $2}' | sort -n | tr '\n' ' '; echo
  echo "t=$(( $(date +%s) - start ))"
done
