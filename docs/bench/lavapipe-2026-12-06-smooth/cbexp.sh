set -u
cd /tmp/cb
export XDG_RUNTIME_DIR=/tmp
S=/work/shared/assets/CornellBox/CornellBox.glb
V="--width 128 --height 128"
[ -f ref.exr ] || /tmp/rk-head render $S $V --spp 4096 --seed 99 --out ref.exr 2>&1 | grep wrote
for seed in 1 2 3 4 5 6; do
  /tmp/rk-head render $S $V --spp 64 --seed $seed --out h64-$seed.exr 2>&1 | grep wrote
  /tmp/rk-smooth render $S $V --spp 64 --seed $seed --out s64-$seed.exr 2>&1 | grep wrote
done
/tmp/venv/bin/python /tmp/tools/relmse.py ref.exr h64 s64
