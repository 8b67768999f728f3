#!/usr/bin/env python3
"""Plots `cloth3d bench --json` output: wall time per frame against particle count.

    cargo run --release --bin cloth3d -- bench --json > bench.json
    python3 scripts/plot_bench.py bench.json docs/bench.png
"""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

rows = [json.loads(line) for line in open(sys.argv[1]) if line.startswith("{")]
series = {}
for r in rows:
    series.setdefault(r["integrator"], []).append((r["n"] * r["n"], 1000.0 * r["frame_wall_s"]))
fig, ax = plt.subplots(figsize=(7, 4.5))
for name, pts in sorted(series.items()):
    pts.sort()
    style = "k--o" if name == "rapier-softbody" else "-o"
    ax.plot([p for p, _ in pts], [t for _, t in pts], style, label=name)
ax.set_xscale("log")
ax.set_yscale("log")
ax.set_xlabel("particles (N x N)")
ax.set_ylabel("wall time per 1/60 s frame (ms)")
ax.set_title("drape: cloth3d integrators vs rapier's built-in soft-body cloth")
ax.axhline(1000 / 60, color="grey", lw=0.8, ls=":")
ax.text(1100, 1000 / 60 * 1.1, "real time (16.7 ms)", color="grey", fontsize=8)
ax.grid(True, which="both", alpha=0.3)
ax.legend()
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=110)
