#!/usr/bin/env bash
# One-time machine set-up for raykin on Debian/Ubuntu: a Vulkan loader and, when no GPU driver is present,
# Mesa's software Vulkan driver (lavapipe) so everything also runs on the CPU; Vulkan's validation layer for the
# tests; Xvfb, xauth and ImageMagick for the viewer's end-to-end test; Intel Open Image Denoise (the `oidn`
# denoiser) from its PyPI wheel into the checkout's .oidn/lib, where raykin loads it at run time. Installs only
# what is missing; safe to run repeatedly.
set -euo pipefail

need=()
ldconfig -p 2>/dev/null | grep -q 'libvulkan\.so\.1' || need+=(libvulkan1)
if ! compgen -G '/usr/share/vulkan/icd.d/*.json' >/dev/null && ! compgen -G '/etc/vulkan/icd.d/*.json' >/dev/null; then
  need+=(mesa-vulkan-drivers)
fi
# The viewer's window test runs under Xvfb and compares X screenshots (ImageMagick's `import`).
command -v xvfb-run >/dev/null && command -v Xvfb >/dev/null || need+=(xvfb)
command -v xauth >/dev/null || need+=(xauth)
command -v import >/dev/null || need+=(imagemagick)
# Vulkan's validation layer: the tests run the commands under it (tests/cli/validation.rs), since lavapipe
# renders some invalid command buffers as if they were valid.
[ -f /usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json ] || need+=(vulkan-validationlayers)
if ((${#need[@]})); then
  echo "setup: installing ${need[*]} (Vulkan loader / software driver / validation layer / Xvfb for the viewer test)" >&2
  sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null
fi
command -v cargo >/dev/null || { echo "setup: cargo not found: install Rust from https://rustup.rs" >&2; exit 1; }

# Intel Open Image Denoise: Debian has no package; the official 2.5.1 libraries (CPU, CUDA, HIP and SYCL
# devices, TBB) ship inside the PyPI wheel `pyoidn`. Only its shared libraries are unpacked, into
# .oidn/lib (git-ignored), which raykin finds by itself (RAYKIN_OIDN_DIR points elsewhere). Without them
# raykin still builds and runs; `--denoise oidn` then says so and uses svgf.
OIDN_VERSION=2.5.1.0
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
oidn_dir="$root/.oidn"
if [ ! -f "$oidn_dir/lib/libOpenImageDenoise.so.2" ] || [ "$(cat "$oidn_dir/VERSION" 2>/dev/null)" != "$OIDN_VERSION" ]; then
  if [ "$(uname -s)-$(uname -m)" != "Linux-x86_64" ]; then
    echo "setup: Open Image Denoise's PyPI wheel is for Linux x86_64 only; the oidn denoiser will be unavailable (svgf stands in)" >&2
  else
    python=$(command -v python3 || true)
    if [ -z "$python" ] || ! "$python" -m pip --version >/dev/null 2>&1; then
      echo "setup: installing python3-pip (to fetch Open Image Denoise from PyPI)" >&2
      sudo=""
      [ "$(id -u)" -ne 0 ] && sudo="sudo"
      $sudo apt-get update -qq
      DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends python3-pip >/dev/null
      python=$(command -v python3)
    fi
    echo "setup: fetching Open Image Denoise (pyoidn==$OIDN_VERSION, ~90 MB) from PyPI into $oidn_dir" >&2
    rm -rf "$oidn_dir/wheel" "$oidn_dir/lib.new"
    "$python" -m pip download --quiet --no-deps --only-binary=:all: --dest "$oidn_dir/wheel" "pyoidn==$OIDN_VERSION"
    # The wheel holds each library under several names as copies; the versioned names are what the
    # libraries ask for (and RAYKIN loads libOpenImageDenoise.so.2), so bare `.so` copies are skipped.
    "$python" - "$oidn_dir" <<'PY'
import glob, os, sys, zipfile
dest = os.path.join(sys.argv[1], "lib.new")
os.makedirs(dest)
(wheel,) = glob.glob(os.path.join(sys.argv[1], "wheel", "pyoidn-*.whl"))
with zipfile.ZipFile(wheel) as z:
    for name in z.namelist():
        base = os.path.basename(name)
        if name.startswith("pyoidn/oidn/lib/") and ".so." in base:
            with open(os.path.join(dest, base), "wb") as f:
                f.write(z.read(name))
    licence = [n for n in z.namelist() if n.endswith("licenses/LICENSE")]
    if licence:
        with open(os.path.join(sys.argv[1], "LICENSE.pyoidn"), "wb") as f:
            f.write(z.read(licence[0]))
PY
    rm -rf "$oidn_dir/lib" "$oidn_dir/wheel"
    mv "$oidn_dir/lib.new" "$oidn_dir/lib"
    echo "$OIDN_VERSION" > "$oidn_dir/VERSION"
  fi
fi
