#!/usr/bin/python3
"""Device-force error of each haptic mode against the reference, from `hapsim sim` outputs.

Usage: scripts/compare_modes.py OUT_JSON OUT_PNG REFERENCE_DIR MODE_DIR...

Each DIR holds a haptic.csv of the same scene and script. Errors are over every haptic step:
RMS and max of |F − F_ref| (3-D), of the normal (z) component and of the tangential (x, y) part.
"""
import csv
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read_forces(folder):
    with open(os.path.join(folder, "haptic.csv")) as f:
        rows = list(csv.DictReader(f))
    t = [float(r["t_s"]) for r in rows]
    force = [(float(r["force_x_N"]), float(r["force_y_N"]), float(r["force_z_N"])) for r in rows]
    return t, force


def errors(force, reference):
    n = min(len(force), len(reference))
    d3 = [math.dist(force[i], reference[i]) for i in range(n)]
    dz = [abs(force[i][2] - reference[i][2]) for i in range(n)]
    dt = [math.hypot(force[i][0] - reference[i][0], force[i][1] - reference[i][1]) for i in range(n)]
    rms = lambda v: math.sqrt(sum(x * x for x in v) / len(v))  # noqa: E731
    return {"rms_N": rms(d3), "max_N": max(d3), "normal_rms_N": rms(dz), "normal_max_N": max(dz),
            "tangential_rms_N": rms(dt), "tangential_max_N": max(dt)}


def main(out_json, out_png, reference_dir, mode_dirs):
    t_ref, f_ref = read_forces(reference_dir)
    result = {"reference": reference_dir, "modes": {}}
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
    top.plot(t_ref, [f[2] for f in f_ref], "k-", lw=2, label="reference")
    bottom.plot(t_ref, [f[0] for f in f_ref], "k-", lw=2, label="reference")
    for folder in mode_dirs:
        t, f = read_forces(folder)
        name = os.path.basename(os.path.normpath(folder))
        result["modes"][name] = errors(f, f_ref)
        top.plot(t, [x[2] for x in f], lw=1, label=name)
        bottom.plot(t, [x[0] for x in f], lw=1, label=name)
    top.set(ylabel="device force z (N)", title="Device force against the reference")
    bottom.set(ylabel="device force x (N)", xlabel="t (s)")
    for axis in (top, bottom):
        axis.grid(True, alpha=0.3)
        axis.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out_png + ".tmp.png", dpi=110)
    os.replace(out_png + ".tmp.png", out_png)
    with open(out_json + ".tmp", "w") as f:
        json.dump(result, f, indent=2)
    os.replace(out_json + ".tmp", out_json)
    for name, e in result["modes"].items():
        print(f"{name:24s} RMS {e['rms_N']:.4f} N (normal {e['normal_rms_N']:.4f}, tangential "
              f"{e['tangential_rms_N']:.4f}), max {e['max_N']:.4f} N")


if __name__ == "__main__":
    if len(sys.argv) < 5:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:])
