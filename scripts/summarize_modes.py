#!/usr/bin/python3
"""A Markdown table and a chart of the haptic modes per scene, from scripts/bench_modes.sh's outputs.

Usage: scripts/summarize_modes.py OUT_DIR OUT_PNG SCENE...

For each scene and mode: the device-force RMS and max error against the reference
(OUT_DIR/SCENE/errors.json, from scripts/compare_modes.py), the median and max wall time of the
haptic step alone and the median visual frame (OUT_DIR/SCENE/MODE/summary.json, `hapsim sim`).
The chart puts each mode's RMS error against its haptic step's median cost, one panel a scene.
"""
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(out_dir, scene):
    with open(os.path.join(out_dir, scene, "errors.json")) as f:
        errors = json.load(f)["modes"]
    rows = []
    for mode in ["reference"] + list(errors):
        with open(os.path.join(out_dir, scene, mode, "summary.json")) as f:
            summary = json.load(f)
        rows.append((mode, errors.get(mode), summary))
    return rows


def main(out_dir, out_png, scenes):
    print("| scene | mode | RMS error (N) | max error (N) | haptic step median / max (µs) "
          "| visual frame median (ms) |")
    print("|---|---|---|---|---|---|")
    fig, axes = plt.subplots(1, len(scenes), figsize=(5 * len(scenes), 4.2))
    for axis, scene in zip(axes, scenes):
        for mode, error, summary in read(out_dir, scene):
            rms = "0 (itself)" if error is None else "%.4f" % error["rms_N"]
            peak = "–" if error is None else "%.3f" % error["max_N"]
            step_us = summary["haptic_step_median_us"]
            step = "%.2f / %.1f" % (step_us, summary["haptic_step_max_us"])
            frame = "%.2f" % summary["frame_stage_median_ms"]["total"]
            print(f"| {scene} | {mode} | {rms} | {peak} | {step} | {frame} |")
            if error is None or step_us <= 0.0:  # the reference; coupling has no 1 kHz work
                continue
            axis.scatter(step_us, error["rms_N"], s=30)
            # penalty and material land close together: one label above, one below.
            axis.annotate(mode, (step_us, error["rms_N"]), fontsize=8,
                          xytext=(4, -11 if mode == "material" else 4), textcoords="offset points")
        axis.set(xscale="log", xlabel="haptic step, median (µs)", ylabel="device-force RMS error (N)",
                 title=scene)
        axis.set_ylim(bottom=0.0)
        axis.grid(True, alpha=0.3)
    fig.suptitle("Haptic modes: device-force error against the 1 kHz reference, and the cost of "
                 "a haptic step (coupling, which has no 1 kHz work, is in the table only)")
    fig.tight_layout()
    fig.savefig(out_png + ".tmp.png", dpi=110)
    os.replace(out_png + ".tmp.png", out_png)


if __name__ == "__main__":
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], sys.argv[3:])
