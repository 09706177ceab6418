#!/usr/bin/env bash
# strip-mitsuba-wheel.sh: a small Mitsuba 3 package for raykin's side-by-side on the lent GPU machine.
#
# Usage: bash strip-mitsuba-wheel.sh MITSUBA_WHEEL OUT.tar.xz
#
# Unpacks a Mitsuba 3 manylinux wheel (made for 3.9.1, cp311/cp312) and writes OUT.tar.xz whose members start
# with `site/`:  tar -C /tmp -xJf OUT.tar.xz  gives /tmp/site/mitsuba/...; install the matching drjit wheel
# into the same folder (pip install --no-index --no-deps --target /tmp/site drjit-*.whl: Mitsuba's libraries
# find drjit's through the RPATH $ORIGIN/../drjit) and run with PYTHONPATH=/tmp/site.
#
# What it keeps, and why:
#   * Variants: cuda_ad_rgb (the GPU comparison) and scalar_rgb (CPU check). Every variant is one compiled
#     Python module, mitsuba/<variant>.cpython-3xx-*.so; the others (llvm_*, *_spectral*, *_mono*) are dropped.
#     (The plugins are one .so each holding every variant, so they cannot be split by variant.)
#     mi.variants() still lists all 13 variants (the list is compiled into mitsuba_alias, not read from
#     config.py); mi.set_variant of a dropped one fails with "No module named 'mitsuba.llvm_ad_rgb'" and the like.
#   * Core libraries: everything a kept module or plugin lists as NEEDED: libmitsuba, libembree3 (linked even
#     for CUDA), libnanobind-drjit, libstruct-jit, libpugixml, libpng/libjpeg-mitsuba and the OpenEXR set
#     (IlmImf, Imath, Half, Iex, IexMath, IlmThread); mitsuba_ext and mitsuba_alias. The script checks the NEEDED
#     closure at the end and fails if a library is missing. Dropped: libIlmImfUtil (nothing links it).
#   * Plugins (mitsuba/plugins/*.so), what scripts/mitsuba-side-by-side.py and gltf_brdf.py load, Mitsuba's
#     own defaults (the plugin names libmitsuba instantiates itself) and a few small related ones:
#       integrator path; samplers independent and ldsampler (the side by side's --sampler); rfilter box,
#       gaussian (hdrfilm's default), lanczos;
#       film hdrfilm; sensor perspective; emitters area, envmap, constant; texture bitmap;
#       BSDFs diffuse (the default BSDF), twosided, normalmap, mask; shapes merge (the scene merges meshes),
#       obj, ply (small mesh loaders); spectra srgb, uniform, d65, irregular, regular; phase isotropic.
#     Meshes built in Python (mi.Mesh) and BSDFs registered with mi.register_bsdf need no further plugin.
#     No blackbody, no other plugin.
#   * Data: data/srgb.coeff only (data/ior and data/sunsky serve dropped plugins). srgb.coeff is the spectral
#     upsampling model: the rgb variants never open it (checked with strace on a scalar_rgb render), and it is
#     about 7.4 MB of the ~19 MB archive (it hardly compresses); `KEEP_DATA= bash strip-mitsuba-wheel.sh ...`
#     leaves it out if the space is needed.
#   * All Python files (.py, and the .pyi stubs) and the dist-info (its RECORD still names dropped files).
#   * Dropped besides: include/, cmake/, pkgconfig/, share/ (docs), the `mitsuba` command-line executable.
#   Shared libraries keep their symbols as shipped (no `strip` run): every kept file is the wheel's, byte for
#   byte; the package only has fewer of them.
set -euo pipefail

if [ $# -ne 2 ]; then
    echo "usage: bash $0 MITSUBA_WHEEL OUT.tar.xz" >&2
    exit 2
fi
WHEEL=$(realpath "$1")
OUT=$(realpath -m "$2")

KEEP_VARIANTS="cuda_ad_rgb scalar_rgb"
KEEP_PLUGINS="path independent ldsampler box gaussian lanczos hdrfilm perspective area envmap constant bitmap
              diffuse twosided normalmap mask merge obj ply srgb uniform d65 irregular regular isotropic"
KEEP_DATA=${KEEP_DATA-srgb.coeff}   # KEEP_DATA= (empty) keeps no data file
# Libraries that may be NEEDED without being in the package: drjit's (in ../drjit) and the system's.
EXTERNAL_OK='^(libdrjit-core\.so|libdrjit-extra\.so|libnanothread\.so|libz\.so\.1|libdl\.so\.2|libstdc\+\+\.so\.6|libm\.so\.6|libgcc_s\.so\.1|libpthread\.so\.0|libc\.so\.6|ld-linux-x86-64\.so\.2)$'

WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
SITE="$WORK/site"
mkdir -p "$SITE"
python3 -m zipfile -e "$WHEEL" "$SITE"
M="$SITE/mitsuba"
[ -f "$M/__init__.py" ] || { echo "$WHEEL: no mitsuba/__init__.py" >&2; exit 1; }

# Variants: drop every <variant>.cpython-*.so not kept (mitsuba_ext / mitsuba_alias are not variants).
for mod in "$M"/*.cpython-*.so; do
    name=$(basename "$mod"); name=${name%%.*}
    case "$name" in mitsuba_ext|mitsuba_alias) continue ;; esac
    keep=0
    for v in $KEEP_VARIANTS; do [ "$name" = "$v" ] && keep=1; done
    [ $keep = 1 ] || rm -f "$mod"
done
for v in $KEEP_VARIANTS; do
    ls "$M"/$v.cpython-*.so >/dev/null 2>&1 || { echo "variant $v not in the wheel" >&2; exit 1; }
done

# Plugins.
for p in "$M"/plugins/*.so; do
    name=$(basename "$p" .so)
    keep=0
    for k in $KEEP_PLUGINS; do [ "$name" = "$k" ] && keep=1; done
    [ $keep = 1 ] || rm -f "$p"
done
for k in $KEEP_PLUGINS; do
    [ -f "$M/plugins/$k.so" ] || { echo "plugin $k not in the wheel" >&2; exit 1; }
done

# Data.
for d in "$M"/data/*; do
    name=$(basename "$d")
    keep=0
    for k in $KEEP_DATA; do [ "$name" = "$k" ] && keep=1; done
    [ $keep = 1 ] || rm -rf "$d"
done

# Build-time and documentation files, the CLI executable, the unlinked OpenEXR utility library.
rm -rf "$M/include" "$M/cmake" "$M/pkgconfig" "$SITE/share" "$M/mitsuba" "$M/libIlmImfUtil-mitsuba.so"
find "$SITE" -name __pycache__ -type d -prune -exec rm -rf {} +

# NEEDED closure: every library a kept ELF file needs is in mitsuba/ or is drjit's / the system's.
missing=0
while IFS= read -r -d '' f; do
    for lib in $(readelf -d "$f" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'); do
        if [ -f "$M/$lib" ]; then continue; fi
        if echo "$lib" | grep -Eq "$EXTERNAL_OK"; then continue; fi
        echo "missing: ${f#$SITE/} needs $lib" >&2
        missing=1
    done
done < <(find "$M" -name '*.so' -print0)
[ $missing = 0 ] || exit 1

mkdir -p "$(dirname "$OUT")"
rm -f "$OUT"
(cd "$WORK" && find site -print0 | LC_ALL=C sort -z |
    tar --null --no-recursion -T - --owner=0 --group=0 --numeric-owner --mtime='2025-01-01 00:00:00' -cf - |
    xz -9e -T0 > "$OUT")
echo "$OUT: $(stat -c %s "$OUT") bytes; unpacked $(du -sb "$SITE" | cut -f1) bytes"
echo "variants: $KEEP_VARIANTS"
echo "plugins: $(cd "$M/plugins" && ls | sed 's/\.so$//' | tr '\n' ' ')"
echo "libraries: $(cd "$M" && ls lib*.so *.cpython-*.so | tr '\n' ' ')"
