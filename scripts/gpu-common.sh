# Sourced by the scripts/gpu-*.sh runs on the lent GPU machine: the output folder ($1, default gpu-out), the
# carried binary (RAYKIN_BIN, default rel/raykin; the run stops when it does not start), the NVIDIA Vulkan
# ICD, the commit the figures are recorded against, and the assets folder (ASSETS, default shared/assets).
out="${1:-gpu-out}"
mkdir -p "$out"
bin="${RAYKIN_BIN:-rel/raykin}"
if ! "$bin" --version >/dev/null 2>&1; then echo "no raykin binary at $bin" >&2; exit 1; fi
if [ -z "${VK_DRIVER_FILES:-}" ] && [ -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ]; then
  export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
fi
export RAYKIN_COMMIT="${RAYKIN_COMMIT:-$(git rev-parse --short HEAD 2>/dev/null || echo unknown)}"
assets="${ASSETS:-shared/assets}"
