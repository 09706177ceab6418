# Sourced first by a device call's script, from the repository root: unpacks what the call carried. The Vulkan
# loader packages in .gl/ (the device README's recipe), the Mitsuba side by side's wheels in .whl/ when carried
# (Dr.Jit's cp312 wheel and mitsuba-strip.tar.xz from scripts/strip-mitsuba-wheel.sh, onto PYTHONPATH), and the
# binaries named as arguments, rel/NAME.xz -> rel/NAME.
for f in .gl/*.deb; do dpkg -x "$f" / ; done
ldconfig
if ls .whl/drjit-*.whl >/dev/null 2>&1; then
  python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site \
    .whl/drjit-*.whl || exit 1
  tar -C /tmp -xJf .whl/mitsuba-strip.tar.xz
  export PYTHONPATH=/tmp/site
fi
for b in "$@"; do (cd rel && xz -dkf "$b.xz" && chmod +x "$b"); done
