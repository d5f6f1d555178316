#!/usr/bin/env bash
# Issue 13 item 5's figures (docs/CONTACT.md, "Which rows travel, and which couple"): what the lcp
# mode's models weigh, and what coupling only the reachable contacts costs, against coupling
# every contact (haptic.lcp_reach_m_s 0). On scenes/block_press.yaml as is, and with its script
# three times faster:
#   - `hapsim sim --mode lcp`: the device force's RMS difference from `hapsim sim --mode
#     reference` (the 1 kHz visual frame) over haptic.csv;
#   - `hapsim run --mode lcp --log`: every CONTACT_MODEL's size, its rows and coupled rows;
# and the fast press of docs/RESULTS.md's map (5 mm in 10 ms, 0.5 m/s, E = 5 MPa): the haptic
# tool's penetration, as scripts/bench/stability_contact.py measures it; and
# scenes/block_press_friction.yaml as is: its models, and lcp's device force beside the coupling
# and linear modes' against its reference.
#
# `hapsim run` crosses processes over LCM: run this in a private network namespace when root,
#   unshare -n bash -c 'ip link set lo up && ip route add 224.0.0.0/4 dev lo && scripts/bench_lcp_rows.sh'
# About 7 minutes on 2 cores (the references take most). Outputs in out/bench_lcp_rows/
# (rows.md: the table). Not part of ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
exec /usr/bin/python3 - "$(git describe --always --dirty)" <<'PY'
import csv, math, os, statistics, struct, subprocess, sys

import numpy as np
import yaml

REV = sys.argv[1]
OUT = "out/bench_lcp_rows"
HAPSIM = "build/apps/hapsim"
os.makedirs(OUT, exist_ok=True)
with open("scenes/block_press.yaml") as f:
    BASE = yaml.safe_load(f)


def variant(name, faster=1.0, reach=None, edit=None):
    """block_press with haptic.mode lcp, the script `faster` times faster, lcp_reach_m_s."""
    scene = yaml.safe_load(yaml.safe_dump(BASE))  # a copy (the block is a lattice: no files)
    scene.setdefault("haptic", {})["mode"] = "lcp"
    if reach is not None:
        scene["haptic"]["lcp_reach_m_s"] = reach
    for waypoint in scene["device"]["trajectory"]:
        waypoint["t_s"] /= faster
    scene["time"]["num_steps"] = int(math.ceil(scene["time"]["num_steps"] / faster))
    if edit:
        edit(scene)
    path = os.path.join(OUT, name + ".yaml")
    with open(path, "w") as f:
        yaml.safe_dump(scene, f)
    return path


def sim(scene, name, mode):
    folder = os.path.join(OUT, name + "_" + mode)
    subprocess.run([HAPSIM, "sim", scene, "--mode", mode, "--out", folder], check=True,
                   stdout=subprocess.DEVNULL)
    with open(os.path.join(folder, "haptic.csv")) as f:
        rows = list(csv.DictReader(f))
    return {key: np.array([float(r[key]) for r in rows]) for key in rows[0]}


def rms(a, b):
    keys = ("force_x_N", "force_y_N", "force_z_N")
    n = min(len(a["t_s"]), len(b["t_s"]))
    d = np.stack([a[k][:n] - b[k][:n] for k in keys], axis=1)
    return float(np.sqrt(np.mean(np.sum(d * d, axis=1))))


def models(scene, name):
    """Sizes, rows and coupled rows of every CONTACT_MODEL of a two-process run's log."""
    log = os.path.join(OUT, name + ".lcm")
    subprocess.run([HAPSIM, "run", scene, "--mode", "lcp", "--log", log], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    data = open(log, "rb").read()
    found, i = [], 0
    while i + 28 <= len(data):  # LCM's event log: sync, number, time, channel and data lengths
        _, _, _, channel_len, data_len = struct.unpack(">IqqII", data[i:i + 28])
        channel = data[i + 28:i + 28 + channel_len].decode()
        message = data[i + 28 + channel_len:i + 28 + channel_len + data_len]
        i += 28 + channel_len + data_len
        if channel != "CONTACT_MODEL":
            continue
        # contact_model_t (messages/contact_model_t.lcm): fingerprint, 3 int64, 23 doubles,
        # num_contacts, 42 doubles, then num_rows, J_v and J_w (6 doubles a row), num_coupled_rows.
        at = 8 + 3 * 8 + 23 * 8 + 4 + 42 * 8
        rows = struct.unpack(">i", message[at:at + 4])[0]
        coupled = struct.unpack(">i", message[at + 4 + 48 * rows:at + 8 + 48 * rows])[0]
        if not (0 <= coupled <= rows):
            sys.exit(f"bench_lcp_rows: {log}: a CONTACT_MODEL this script cannot read")
        found.append((len(message), rows, coupled))
    return {"peak_kB": max(m[0] for m in found) / 1e3,
            "median_kB": statistics.median(m[0] for m in found) / 1e3,
            "rows": max(m[1] for m in found), "coupled": max(m[2] for m in found)}


def fast_press(scene_path, name):
    """The haptic tool's depth past the visual tool's, mm (stability_contact.py's fast_run)."""
    top_plus_half = BASE["body"]["mesh"]["box"]["max_m"][2] + \
        BASE["tool"]["shape"]["cylinder"]["length_m"] / 2
    h = sim(scene_path, name, "lcp")
    with open(os.path.join(OUT, name + "_lcp", "frames.csv")) as f:
        frames = [float(r["tool_z_m"]) for r in csv.DictReader(f)]
    visual_sink = max(0.0, max(top_plus_half - z for z in frames))
    return 1e3 * max(0.0, float((top_plus_half - h["tool_z_m"]).max()) - visual_sink)


def press_fast(scene):
    z0 = scene["tool"]["position_m"][2]
    scene["body"]["material"]["youngs_modulus_Pa"] = 5e6
    scene["device"]["trajectory"] = [
        {"t_s": 0.0, "position_m": [0.0, 0.0, z0]}, {"t_s": 0.1, "position_m": [0.0, 0.0, z0]},
        {"t_s": 0.11, "position_m": [0.0, 0.0, z0 - 0.005]},
        {"t_s": 0.41, "position_m": [0.0, 0.0, z0 - 0.005]}]
    scene["time"]["num_steps"] = int(math.ceil(0.41 / scene["time"]["dt_s"]))


lines = [f"tree {REV}; block_press, lcp; RMS of the device force from the 1 kHz reference",
         "", "| case | rows, peak (coupled) | model, peak / median | RMS vs reference |",
         "|---|---|---|---|"]
for faster, label in ((1.0, "the script"), (3.0, "the script 3× faster")):
    tag = "x1" if faster == 1.0 else "x3"
    print(f"bench_lcp_rows: {label}: reference", file=sys.stderr, flush=True)
    reference = sim(variant(f"{tag}_reference", faster), f"{tag}_reference", "reference")
    for reach, what in ((0.0, "every contact coupled"), (None, "reachable ones coupled (default)")):
        name = f"{tag}_reach_{'all' if reach == 0.0 else 'default'}"
        print(f"bench_lcp_rows: {label}, {what}", file=sys.stderr, flush=True)
        scene = variant(name, faster, reach)
        m = models(scene, name)
        lines.append(f"| {label}, {what} | {m['rows']} ({m['coupled']}) | "
                     f"{m['peak_kB']:.1f} / {m['median_kB']:.1f} kB | "
                     f"{rms(sim(scene, name, 'lcp'), reference):.4f} N |")
print("bench_lcp_rows: fast press", file=sys.stderr, flush=True)
lines += ["", "fast press (5 mm in 10 ms, 0.5 m/s, E = 5 MPa), haptic tool penetration: " +
          ", ".join(f"{what} {fast_press(variant('fast_' + tag, 1.0, reach, press_fast), 'fast_' + tag):.3f} mm"
                    for reach, tag, what in ((0.0, "all", "every contact coupled"),
                                             (None, "default", "reachable ones coupled")))]
# block_press_friction as is (three rows per contact, the default reach): its models, and the
# device force of lcp beside coupling and linear against its reference (~4 min of the run).
print("bench_lcp_rows: block_press_friction", file=sys.stderr, flush=True)
friction = "scenes/block_press_friction.yaml"
m = models(friction, "friction")
reference = sim(friction, "friction", "reference")
errors = ", ".join(f"{mode} {rms(sim(friction, 'friction', mode), reference):.4f} N"
                   for mode in ("lcp", "coupling", "linear"))
lines += ["", f"block_press_friction: rows {m['rows']} at peak ({m['coupled']} coupled), model "
          f"{m['peak_kB']:.1f} / {m['median_kB']:.1f} kB peak / median; RMS vs reference: {errors}"]
with open(os.path.join(OUT, "rows.md"), "w") as f:
    f.write("\n".join(lines) + "\n")
print("\n".join(lines))
PY
