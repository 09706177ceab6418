#!/usr/bin/env bash
# Device call: is the crowd's loss under texture wrapping per axis (t2) the alpha test's texture lookup inlined in
# the traversal loops? An ablation, not a candidate: `a` = the alpha test without the base-colour texture's
# alpha (scene/alpha.wgsl; wrong on alpha-masked textures, but no material of these scenes is masked, so their
# images are unchanged: only the code inlined in the traversal loops is), `t2` = per-axis wrapping, `t2a` = both. Binary of 64c8d5b, kernel variants through
# RAYKIN_SHADER_DIR (rel/var/*), two rounds. Carry .gl and rel.
set -u
ASSETS=rel/assets SCENES="cornell flight-helmet crowd" bash scripts/gpu-ab-frames.sh 2 \
  raykin-h raykin-h:rel/var/t2 raykin-h:rel/var/a raykin-h:rel/var/t2a
