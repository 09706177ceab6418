# Sourced first by a device call's script, from the repository root: unpacks what the call carried (made here by
# scripts/gpu-pack.sh). The Vulkan loader packages in .gl/ (the device README's recipe), the Mitsuba side by
# side's wheels in .whl/ when carried (Dr.Jit's cp312 wheel and mitsuba-strip.tar.xz from
# scripts/strip-mitsuba-wheel.sh, onto PYTHONPATH), the binaries named as arguments, rel/NAME.xz -> rel/NAME, and
# relb/head.xz -> relb/head when carried. Then what every call needs next: the NVIDIA Vulkan driver for the loader,
# the card in $OUT/gpu.txt, `elapsed` (seconds since this ran) for the scripts' time budgets, and `frame_rows`.
start=$(date +%s)
elapsed() { echo $(( $(date +%s) - start )); }
# The bench's frame loop for one variant: frame_rows LABEL FILE BINARY ENV=VALUE BENCH-OPTIONS... appends a row per
# scene to $OUT/FILE (label, scene, width, spp per frame, trace ms median, form, auto's trial ms), or the log's
# tail to $OUT/errors.txt. Assets from relb/assets.
frame_rows() {
  local w; w=$(mktemp -d); local label=$1 file=$2 bin=$3 envs=$4; shift 4
  env "$envs" "$bin" bench --suite full --parts frames "$@" --assets relb/assets --out "$w" --cache "$w/c" \
    > "$w/log" 2>&1
  python3 -c "
import json; r=json.load(open('$w/results.json'))
for row in r['rows']: print('$label', row['scene'], row['width'], row['spp_per_frame'], row['trace_ms_median'], row['integrator'], row.get('auto_trial_ms'))
" >> "$OUT/$file" || tail -5 "$w/log" >> "$OUT/errors.txt"
}
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
# The commit relb/head was built from (scripts/gpu-pack.sh), which the bench records.
if [ -f relb/commit ]; then export RAYKIN_COMMIT="$(cat relb/commit)"; fi
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
if [ -n "${OUT:-}" ]; then
  nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv > "$OUT/gpu.txt"
fi
