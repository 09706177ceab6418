#!/usr/bin/env python3
"""Per scene and curve of a bench results.json: relMSE x time (median over the curve's second half of
checkpoints, the reference's noise subtracted) relative to the default curve, with relMSE x spp (variance) and
trace ms per spp beside it. Usage: efficiency.py results.json"""
import json
import statistics
import sys

r = json.load(open(sys.argv[1]))
for s in r["error_vs_time"]:
    noise = s.get("reference_noise_rel_mse") or 0.0
    rows = []
    for c in s["curves"]:
        pts = c["points"]
        half = pts[len(pts) // 2:]
        eff = statistics.median(max(p["rel_mse"] - noise, 1e-12) * p["time_ms"] for p in half)
        var = statistics.median(max(p["rel_mse"] - noise, 1e-12) * p["spp"] for p in half)
        ms = half[-1]["time_ms"] / half[-1]["spp"]
        rows.append((c["name"], eff, var, ms))
    base = rows[0]
    print(f"{s['scene']} ({s['width']}x{s['height']}, reference noise {noise:.2e})")
    print("| curve | relMSE x time | ratio | variance ratio | trace ms/spp ratio |")
    print("|---|---|---|---|---|")
    for name, eff, var, ms in rows:
        print(f"| {name} | {eff:.4g} | {eff / base[1]:.3f} | {var / base[2]:.3f} | {ms / base[3]:.3f} |")
    print()
