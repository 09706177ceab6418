# usage: envexp.sh NAME ENVARGS...   (in /tmp/fh)
set -u
cd /tmp/fh
export XDG_RUNTIME_DIR=/tmp
FH=${SCENE:-/work/shared/assets/FlightHelmet/glTF/FlightHelmet.gltf}
V=${VIEW:---width 128 --height 72 --look-from=-0.0204,0.4244,1.1720 --look-at=-0.0204,0.3580,0.0142 --fov 45}
name=$1; shift
mkdir -p $name
[ -f $name/ref.exr ] || /tmp/rk-head render $FH $V "$@" --spp 4096 --seed 99 --out $name/ref.exr 2>&1 | grep -E "peak|wrote"
for seed in 1 2 3 4 5 6; do
  RAYKIN_SMOOTH_PEAK=0 /tmp/rk-var render $FH $V "$@" --spp 64 --seed $seed --out $name/h64-$seed.exr 2>&1 | grep -E "wrote" 
  RAYKIN_SMOOTH_PEAK=1e9 /tmp/rk-var render $FH $V "$@" --spp 64 --seed $seed --out $name/v64-$seed.exr 2>&1 | grep -E "wrote"
done
/tmp/venv/bin/python /tmp/tools/relmse.py $name/ref.exr $name/h64 $name/v64
