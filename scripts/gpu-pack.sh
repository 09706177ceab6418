#!/usr/bin/env bash
# What a device call carries, made on this machine (scripts/gpu-unpack.sh unpacks it there):
#   relb/head.xz   the stripped release binary of the working tree, xz-compressed;
#   relb/commit    the commit it was built from (`-dirty` with uncommitted changes): the device's copy of the
#                  repository's history can lag behind the working tree, so the figures name this one;
#   relb/assets/   the bench's glTF assets from ../shared/assets (CornellBox, FlightHelmet, the spheres, CesiumMan,
#                  Fox: what the static scenes, the crowd and the seed-like interior load);
#   .gl/           the Vulkan loader and GL dispatch packages for amd64 (the device README's recipe: the machine
#                  has the NVIDIA driver's ICD but no loader);
#   .whl/          with --mitsuba: Dr.Jit 1.5.0's cp312 wheel and Mitsuba 3.9.1's stripped by
#                  scripts/strip-mitsuba-wheel.sh, for scripts/gpu-mitsuba.sh.
# Everything comes from the package registries (Debian, PyPI). Then: run with carry [".gl", "relb"] (and ".whl").
#   bash scripts/gpu-pack.sh [--mitsuba]
set -euo pipefail
cd "$(dirname "$0")/.."
mitsuba=${1:-}
cargo build --release -p raykin
mkdir -p relb
strip -o relb/head target/release/raykin
xz -T2 -6 -f relb/head
echo "$(git rev-parse --short HEAD)$(git diff --quiet HEAD -- || echo -dirty)" > relb/commit
mkdir -p relb/assets
for asset in CornellBox FlightHelmet MetalRoughSpheresNoTextures CesiumMan Fox; do
  rm -rf "relb/assets/$asset"
  cp -r "../shared/assets/$asset" relb/assets/
done
if ! ls .gl/libvulkan1_*.deb >/dev/null 2>&1; then
  lists=$(mktemp -d)
  mkdir -p .gl "$lists/partial"
  apt=(-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 "-oDir::State::Lists=$lists")
  apt-get "${apt[@]}" update >/dev/null
  (cd .gl && apt-get "${apt[@]}" download libvulkan1 libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
  rm -rf "$lists"
fi
if [ "$mitsuba" = --mitsuba ] && ! [ -f .whl/mitsuba-strip.tar.xz ]; then
  wheels=$(mktemp -d)
  python3 -m pip download --quiet --no-deps --only-binary=:all: --platform manylinux_2_28_x86_64 \
    --python-version 3.12 --implementation cp drjit==1.5.0 mitsuba==3.9.1 -d "$wheels"
  mkdir -p .whl
  cp "$wheels"/drjit-*.whl .whl/
  KEEP_DATA= bash scripts/strip-mitsuba-wheel.sh "$wheels"/mitsuba-3.9.1-*.whl .whl/mitsuba-strip.tar.xz
  rm -rf "$wheels"
fi
du -sh relb .gl .whl 2>/dev/null || true
