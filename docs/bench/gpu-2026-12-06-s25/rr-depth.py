#!/usr/bin/env python3
"""Russian roulette's start by measurement: per scene and curve, relMSE x trace time (median over the curve's
second half of checkpoints, the run's own reference noise subtracted), relMSE x spp (variance) and trace ms per spp
of each `--rr-depth` run, as ratios to depth 4 (the default). Usage: rr-depth.py DIR [CURVE], DIR holding
ROUND-DEPTH/results.json; CURVE: a part of the curve's name (default: the first curve, the bench's default)."""
import json
import pathlib
import statistics
import sys

wanted = sys.argv[2] if len(sys.argv) > 2 else None
runs = {}
for f in sorted(pathlib.Path(sys.argv[1]).glob("*-*/results.json")):
    round_, depth = f.parent.name.split("-")
    for s in json.load(open(f))["error_vs_time"]:
        noise = s.get("reference_noise_rel_mse") or 0.0
        curves = [c for c in s["curves"] if wanted is None or wanted in c["name"]]
        if not curves:
            continue
        c = curves[0]
        half = c["points"][len(c["points"]) // 2:]
        eff = statistics.median(max(p["rel_mse"] - noise, 1e-12) * p["time_ms"] for p in half)
        var = statistics.median(max(p["rel_mse"] - noise, 1e-12) * p["spp"] for p in half)
        ms = half[-1]["time_ms"] / half[-1]["spp"]
        runs.setdefault((s["scene"], int(depth)), []).append((round_, eff, var, ms, c["integrator"], c["name"]))
print("| scene | curve | rr depth | round | relMSE x time | ratio to depth 4 | variance ratio | ms/spp ratio | form |")
print("|---|---|---|---|---|---|---|---|---|")
for (scene, depth), rows in sorted(runs.items()):
    base = {r[0]: r for r in runs.get((scene, 4), [])}
    for round_, eff, var, ms, form, name in rows:
        b = base.get(round_)
        ratio = lambda x, i: f"{x / b[i]:.3f}" if b else "-"
        print(f"| {scene} | {name} | {depth} | {round_} | {eff:.4g} | {ratio(eff, 1)} | {ratio(var, 2)} | {ratio(ms, 3)} | {form} |")
