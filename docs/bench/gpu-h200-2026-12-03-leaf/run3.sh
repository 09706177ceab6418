#!/usr/bin/env bash
# (The variant folders rel/var/{t1,t2,t3,c} are kept here as variants/*.wgsl; leaf-triangles.patch is raykin-b.)
# Device call 3: texture wrapping variants on every bench scene, raykin-a (45cb732) with scene/texture.wgsl as is,
# t2 (each axis wrapped once: integer remainder) and t3 (t2 with the repeat/repeat case folded in floating point),
# alternating twice. Both variants give byte-identical images on lavapipe (TextureSettingsTest, FlightHelmet,
# TextureTransformTest).
set -u
SCENES="cornell flight-helmet spheres crowd seed-interior" bash scripts/gpu-ab-frames.sh 2 \
  raykin-a raykin-a:rel/var/t2 raykin-a:rel/var/t3
