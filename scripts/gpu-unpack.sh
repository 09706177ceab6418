# Sourced first by a device call's script, from the repository root: unpacks what the call carried (made here by
# scripts/gpu-pack.sh). The Vulkan loader packages in .gl/ (the device README's recipe), the Mitsuba side by
# side's wheels in .whl/ when carried (Dr.Jit's cp312 wheel and mitsuba-strip.tar.xz from
# scripts/strip-mitsuba-wheel.sh, onto PYTHONPATH), the binaries named as arguments, rel/NAME.xz -> rel/NAME, and
# relb/head.xz -> relb/head when carried. Then what every call needs next: the NVIDIA Vulkan driver for the loader,
# the card in $OUT/gpu.txt, and `elapsed` (seconds since this ran) for the scripts' time budgets.
start=$(date +%s)
elapsed() { echo $(( $(date +%s) - start )); }
for f in .gl/*.deb; do dpkg -x "$f" / ; done
ldconfig
if ls .whl/drjit-*.whl >/dev/null 2>&1; then
  python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site \
    .whl/drjit-*.whl || exit 1
  tar -C /tmp -xJf .whl/mitsuba-strip.tar.xz
  export PYTHONPATH=/tmp/site
fi
for b in "$@"; do (cd rel && xz -dkf "$b.xz" && chmod +x "$b"); done
if [ -f relb/head.xz ]; then (cd relb && xz -dkf head.xz && chmod +x head); fi
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
if [ -n "${OUT:-}" ]; then
  nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv > "$OUT/gpu.txt"
fi
