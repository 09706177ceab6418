#!/usr/bin/env bash
# One-time machine set-up for raykin on Debian/Ubuntu: a Vulkan loader and, when no GPU driver is present,
# Mesa's software Vulkan driver (lavapipe) so everything also runs on the CPU; Xvfb, xauth and ImageMagick for
# the viewer's end-to-end test. Installs only what is missing; safe to run repeatedly.
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
if ((${#need[@]})); then
  echo "setup: installing ${need[*]} (Vulkan loader / software driver / Xvfb for the viewer test)" >&2
  sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null
fi
command -v cargo >/dev/null || { echo "setup: cargo not found: install Rust from https://rustup.rs" >&2; exit 1; }
