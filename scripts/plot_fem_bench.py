#!/usr/bin/python3
"""Charts of `hapsim fem --bench` output: speed beside accuracy.

Usage: scripts/plot_fem_bench.py out/bench/fem_bench.json out/bench/fem_bench.png

Left: mean time per implicit step against tet count, per solver (log-log).
Right: mean time per step against the probe-trajectory error relative to the direct CHOLMOD
solve, one point per (scene, solver); CHOLMOD itself is the reference and is drawn at the
bottom edge of the axis.
"""
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "bench"))
from common import place_labels  # noqa: E402  (labels that do not sit on one another)


def main(json_path, png_path):
    with open(json_path) as f:
        bench = json.load(f)
    rows = bench["rows"]
    solvers = sorted({r["solver"] for r in rows})
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    floor = 1e-12  # where the reference (zero error) is drawn on the log axis
    labels = []
    for solver in solvers:
        mine = sorted((r for r in rows if r["solver"] == solver), key=lambda r: r["num_tets"])
        left.plot([r["num_tets"] for r in mine], [r["mean_ms"] for r in mine], "o-", label=solver)
        # CHOLMOD is the reference (error 0): say in the legend where it is drawn.
        name = f"{solver} (reference, drawn at {floor:g})" if solver == "cholmod" else solver
        points = right.plot([max(r["relative_difference_from_cholmod"], floor) for r in mine],
                            [r["mean_ms"] for r in mine], "o", label=name)
        labels += [(max(r["relative_difference_from_cholmod"], floor), r["mean_ms"],
                    str(r["num_tets"]), points[0].get_color()) for r in mine]
    left.set(xscale="log", yscale="log", xlabel="tets", ylabel="mean time per step (ms)",
             title="Implicit step, reference blocks")
    right.set(xscale="log", yscale="log", xlabel="probe trajectory error vs CHOLMOD (relative)",
              ylabel="mean time per step (ms)", title="Speed against accuracy")
    for axis in (left, right):
        axis.grid(True, which="both", alpha=0.3)
        axis.legend(fontsize=8)
    machine = bench.get("machine", {})
    fig.suptitle(f"{machine.get('cpu', '?')}, {machine.get('date', '?')}", fontsize=9)
    place_labels(right, labels)  # lays the figure out (tight_layout) before measuring
    tmp = png_path + ".tmp.png"
    fig.savefig(tmp, dpi=120)
    os.replace(tmp, png_path)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
