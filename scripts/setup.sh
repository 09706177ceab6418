#!/usr/bin/env bash
# One-time machine set-up for raykin on Debian/Ubuntu: a Vulkan loader and, when no GPU driver is present,
# Mesa's software Vulkan driver (lavapipe) so everything also runs on the CPU. Safe to run repeatedly.
set -euo pipefail

need=()
ldconfig -p 2>/dev/null | grep -q 'libvulkan\.so\.1' || need+=(libvulkan1)
if ! ls /usr/share/vulkan/icd.d/*.json /etc/vulkan/icd.d/*.json >/dev/null 2>&1; then
  need+=(mesa-vulkan-drivers)
fi
if ((${#need[@]})); then
  echo "setup: installing ${need[*]} (Vulkan loader / software driver)" >&2
  sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${need[@]}" >/dev/null
fi
command -v cargo >/dev/null || { echo "setup: cargo not found: install Rust from https://rustup.rs" >&2; exit 1; }
