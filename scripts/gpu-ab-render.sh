#!/usr/bin/env bash
# Same-call A/B of two raykin builds (rel/raykin-old.xz, rel/raykin-new.xz, carried with .gl and shared/):
# Cornell box and FlightHelmet renders, the builds alternated three times; prints M samples/s per render.
#   for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig; bash scripts/gpu-ab-render.sh
set -u
for b in old new; do xz -d -k -f rel/raykin-$b.xz; chmod +x rel/raykin-$b; done
C=shared/assets/CornellBox/CornellBox.glb
F=shared/assets/FlightHelmet/glTF/FlightHelmet.gltf
for round in 1 2 3; do
  for b in old new; do
    echo -n "round $round $b cornell: "; rel/raykin-$b render $C --look-from=-278,273,800 --look-at=-278,273,0 --fov 39.3077 --env 0,0,0 --width 1024 --height 1024 --spp 256 --spp-per-dispatch 16 --out /tmp/c-$b.exr 2>&1 | grep -o "[0-9.]* M samples/s"
    echo -n "round $round $b helmet: "; rel/raykin-$b render $F --width 1024 --height 1024 --spp 256 --spp-per-dispatch 16 --out /tmp/f-$b.exr 2>&1 | grep -o "[0-9.]* M samples/s"
  done
done
