#!/usr/bin/env bash
# Device call (H200): MIS-compensated environment sampling for next-event estimation, same-call A/B of the
# error part. raykin-old = f5f953c (NEE samples the full environment distribution), raykin-new = 0575c1d (NEE
# samples the compensated one; a uniform map is left to BSDF sampling). Each binary renders its own reference
# (the cache key holds the kernel source); curves: the default (1 spp/frame) and 16 spp/frame. Order old, new,
# new, old so that neither always runs first. Carry .gl and rel.
set -u
OUT=${OUT:-gpu-out}; mkdir -p "$OUT"
for f in .gl/*.deb; do dpkg -x "$f" / ; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
(cd rel && for b in raykin-old raykin-new; do xz -dkf $b.xz && chmod +x $b; done)
scenes="--scene spheres --scene env-lit --scene flight-helmet"
k=0
for b in raykin-old raykin-new raykin-new raykin-old; do
  k=$((k + 1))
  start=$SECONDS
  rel/$b bench --suite full --parts errors $scenes --curve "16 spp/frame" --assets shared/assets \
    --out "$OUT/err-$k-$b" --cache "/tmp/cache-$b" > "$OUT/err-$k-$b.log" 2>&1
  echo "$k $b $((SECONDS - start)) s" >> "$OUT/marks.txt"
  # Four runs must fit the call's 600 s: stop after the first pair when it took over 270 s.
  [ $k = 2 ] && [ $SECONDS -gt 270 ] && break
done
for d in "$OUT"/err-*; do
  python3 - "$d/results.json" "$(basename "$d")" <<'PY' >> "$OUT/summary.txt"
import json, sys
r = json.load(open(sys.argv[1]))
for e in r.get('error_vs_time', []):
    for c in e['curves']:
        last = c['points'][-1]
        print(sys.argv[2], e['scene'], c['name'][:20].replace(' ', '_'), 'ref_noise', '%.3g' % e['reference_noise_rel_mse'],
              'spp', last['spp'], 'ms', round(last['time_ms'], 1), 'relmse', '%.4g' % last['rel_mse'],
              'lin', '%.4g' % last['rel_mse_linear'], 'ms_to_0.01', c.get('ms_to_rel_mse_0_01'))
PY
done
cat "$OUT/marks.txt" "$OUT/summary.txt"
find "$OUT" -name cache -prune -exec rm -rf {} \;
tar -C "$OUT" -cJf "/tmp/run1.tar.xz" . && mv /tmp/run1.tar.xz "$OUT/"
