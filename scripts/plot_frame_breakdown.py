#!/usr/bin/python3
"""Visual-frame cost against contact count, from `hapsim sim` frames.csv files.

Usage: scripts/plot_frame_breakdown.py OUT_PNG LABEL=FRAMES_CSV [LABEL=FRAMES_CSV ...]

Left: each stage of the first run (free FEM, detection, response, linear model, sanity pass) and
the whole frame, one point per visual frame, against the number of contacts in the frame.
Right: the whole frame of every run against contacts (e.g. warped against exact compliance).
Frames that refactorised the FEM preconditioner stand out as the high free-FEM points.
"""
import csv
import os
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

STAGES = [("free_fem_ms", "free FEM"), ("detection_ms", "detection"),
          ("response_ms", "response"), ("model_ms", "linear model"), ("sanity_ms", "sanity pass"),
          ("total_ms", "whole frame")]


def read_frames(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return [r for r in rows if int(r["contacts"]) > 0]


def print_bins(label, frames):
    """The table of docs/BENCHMARKS.md: stage medians by contact count, and the target's figure."""
    print(f"{label}: medians, ms")
    print("| contacts | frames | free FEM | detection | response | linear model | whole frame |")
    for lo, hi in [(1, 100), (100, 160), (160, 200), (200, 10**9)]:
        sel = [r for r in frames if lo <= int(r["contacts"]) < hi]
        if sel:
            med = lambda key: statistics.median(float(r[key]) for r in sel)  # noqa: E731
            print(f"| {lo}-{hi - 1 if hi < 10**9 else ''} | {len(sel)} | {med('free_fem_ms'):.2f} | "
                  f"{med('detection_ms'):.2f} | {med('response_ms'):.2f} | {med('model_ms'):.2f} | "
                  f"{med('total_ms'):.2f} |")
    many = [float(r["total_ms"]) for r in frames if int(r["contacts"]) >= 100]
    if many:
        print(f"whole frame, median over the {len(many)} frames with >= 100 contacts: "
              f"{statistics.median(many):.2f} ms")


def main(out_png, runs):
    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.5))
    first_label, first_path = runs[0]
    frames = read_frames(first_path)
    for label, path in runs:
        print_bins(label, read_frames(path))
    contacts = [int(r["contacts"]) for r in frames]
    for key, name in STAGES:
        left.scatter(contacts, [float(r[key]) for r in frames], s=10, label=name)
    left.set(xlabel="contacts in the frame", ylabel="ms", yscale="log",
             title=f"Stages of the visual frame ({first_label})")
    for label, path in runs:
        frames = read_frames(path)
        right.scatter([int(r["contacts"]) for r in frames], [float(r["total_ms"]) for r in frames],
                      s=10, label=label)
    right.set(xlabel="contacts in the frame", ylabel="whole frame, ms", title="Whole frame")
    for axis in (left, right):
        axis.grid(True, alpha=0.3)
        axis.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out_png + ".tmp.png", dpi=110)
    os.replace(out_png + ".tmp.png", out_png)


if __name__ == "__main__":
    if len(sys.argv) < 3 or any("=" not in a for a in sys.argv[2:]):
        sys.exit(__doc__)
    main(sys.argv[1], [tuple(a.split("=", 1)) for a in sys.argv[2:]])
