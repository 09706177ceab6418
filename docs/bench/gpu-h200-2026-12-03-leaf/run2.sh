#!/usr/bin/env bash
# (The variant folders rel/var/{t1,t2,t3,c} are kept here as variants/*.wgsl; leaf-triangles.patch is raykin-b.)
# Device call 2: kernel variants through RAYKIN_SHADER_DIR (rel/var/*), same binaries as run1.sh.
# texture: raykin-a with scene/texture.wgsl as is, t2 (each axis wrapped once per bilinear lookup: same texels,
# same images) and t1 (nearest filtering everywhere: an ablation measuring what bilinear costs, not a keepable
# change), three rounds on the textured scenes. leaf: raykin-b as in run1 and c (leaf triangles read without the
# per-triangle branch: valid only where every mesh is static), two rounds on the static scenes.
set -u
mkdir -p "$OUT/texture" "$OUT/leaf"
OUT="$OUT/texture" SCENES="flight-helmet crowd seed-interior" bash scripts/gpu-ab-frames.sh 3 \
  raykin-a raykin-a:rel/var/t2 raykin-a:rel/var/t1
OUT="$OUT/leaf" SCENES="cornell flight-helmet spheres" bash scripts/gpu-ab-frames.sh 2 \
  raykin-a raykin-b raykin-b:rel/var/c
