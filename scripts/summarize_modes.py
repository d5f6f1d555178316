#!/usr/bin/python3
"""A Markdown table of the haptic modes per scene, from the outputs of scripts/bench_modes.sh.

Usage: scripts/summarize_modes.py OUT_DIR SCENE...

For each scene and mode: the device-force RMS and max error against the reference
(OUT_DIR/SCENE/errors.json, from scripts/compare_modes.py), the median and max wall time of the
haptic step alone and the median visual frame (OUT_DIR/SCENE/MODE/summary.json, `hapsim sim`).
"""
import json
import os
import sys


def main(out_dir, scenes):
    print("| scene | mode | RMS error (N) | max error (N) | haptic step median / max (µs) "
          "| visual frame median (ms) |")
    print("|---|---|---|---|---|---|")
    for scene in scenes:
        with open(os.path.join(out_dir, scene, "errors.json")) as f:
            errors = json.load(f)["modes"]
        for mode in ["reference"] + list(errors):
            with open(os.path.join(out_dir, scene, mode, "summary.json")) as f:
                summary = json.load(f)
            error = errors.get(mode)
            rms = "0 (itself)" if error is None else "%.4f" % error["rms_N"]
            peak = "–" if error is None else "%.3f" % error["max_N"]
            step = "%.2f / %.1f" % (summary["haptic_step_median_us"], summary["haptic_step_max_us"])
            frame = "%.2f" % summary["frame_stage_median_ms"]["total"]
            print(f"| {scene} | {mode} | {rms} | {peak} | {step} | {frame} |")


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2:])
