#!/usr/bin/env bash
# Issue 13 item 5's figures (docs/CONTACT.md, "Which rows travel, and which couple"): what the lcp
# mode's models weigh, and what coupling only the reachable contacts costs, against coupling
# every contact (haptic.lcp_reach_m_s 0). On scenes/block_press.yaml as is, and with its script
# three times faster:
#   - `hapsim sim --mode lcp`: the device force's RMS difference from `hapsim sim --mode
#     reference` (the 1 kHz visual frame) over haptic.csv;
#   - `hapsim run --mode lcp --log`: every CONTACT_MODEL's size, its rows and coupled rows;
# and the fast press of docs/RESULTS.md's map (5 mm in 10 ms, 0.5 m/s, E = 5 MPa): the haptic
# tool's penetration, by scripts/bench/stability_contact.py's fast_run; and
# scenes/block_press_friction.yaml as is: its models, and lcp's device force beside the coupling
# and linear modes' against its reference. Runs and scene variants go through scripts/bench's
# Bench, the force error through compare_modes.errors, as bench.sh's experiments do.
#
# `hapsim run` crosses processes over LCM: run this in a private network namespace when root,
#   unshare -n bash -c 'ip link set lo up && ip route add 224.0.0.0/4 dev lo && scripts/bench_lcp_rows.sh'
# About 6 minutes on 2 cores (the references take most). Outputs in out/bench_lcp_rows/
# (rows.md: the table; runs/ and scenes/ as bench.sh writes them). Not part of ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
exec /usr/bin/python3 - "$(git describe --always --dirty)" <<'PY'
import os, statistics, struct, sys

sys.path[:0] = ["scripts", "scripts/bench"]
from common import Bench, REPO  # noqa: E402
from compare_modes import errors, read_forces  # noqa: E402
from stability_contact import fast_run  # noqa: E402
from stability_common import PRESS, press_scene  # noqa: E402

REV = sys.argv[1]
bench = Bench(os.path.join(REPO, "build/apps/hapsim"), os.path.join(REPO, "out/bench_lcp_rows"),
              quick=False)
BASE = press_scene()
FRICTION = "scenes/block_press_friction.yaml"


def variant(name, faster=1.0, reach=None):
    """block_press with its script `faster` times faster and haptic.lcp_reach_m_s `reach`."""
    edits = {"device.trajectory": [dict(w, t_s=w["t_s"] / faster)
                                   for w in BASE["device"]["trajectory"]],
             "time.num_steps": -(-BASE["time"]["num_steps"] // int(faster))}
    if reach is not None:
        edits["haptic.lcp_reach_m_s"] = reach
    return bench.scene_variant(PRESS, edits, name)


def rms_vs(scene, name, mode, reference_folder):
    """The device force's RMS difference (N) of `hapsim sim --mode MODE` from the reference's."""
    _, _, folder = bench.sim(scene, f"{name}_{mode}", "--mode", mode)
    return errors(read_forces(folder)[1], read_forces(reference_folder)[1])["rms_N"]


def models(scene, name):
    """Sizes, rows and coupled rows of every CONTACT_MODEL of a two-process run's log."""
    log = bench.path(name + ".lcm")
    bench.hapsim_run("run", scene, "--mode", "lcp", "--log", log)
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


lines = [f"tree {REV}; block_press, lcp; RMS of the device force from the 1 kHz reference",
         "", "| case | rows, peak (coupled) | model, peak / median | RMS vs reference |",
         "|---|---|---|---|"]
for faster, label in ((1, "the script"), (3, "the script 3× faster")):
    tag = f"x{faster}"
    bench.progress(f"{label}: reference")
    _, _, reference = bench.sim(variant(f"{tag}_reference", faster), f"{tag}_reference",
                                "--mode", "reference")
    for reach, what in ((0.0, "every contact coupled"), (None, "reachable ones coupled (default)")):
        name = f"{tag}_reach_{'all' if reach == 0.0 else 'default'}"
        bench.progress(f"{label}, {what}")
        scene = variant(name, faster, reach)
        m = models(scene, name)
        lines.append(f"| {label}, {what} | {m['rows']} ({m['coupled']}) | "
                     f"{m['peak_kB']:.1f} / {m['median_kB']:.1f} kB | "
                     f"{rms_vs(scene, name, 'lcp', reference):.4f} N |")
# The fast press of docs/RESULTS.md's map, as stability_contact.py runs it.
bench.progress("fast press")
press = [(what, fast_run(bench, "lcp", 5e6, 0.01, edits=edits, tag=tag)["haptic_penetration_m"])
         for edits, tag, what in (({"haptic.lcp_reach_m_s": 0.0}, "_reach_all",
                                   "every contact coupled"),
                                  ({}, "", "reachable ones coupled"))]
lines += ["", "fast press (5 mm in 10 ms, 0.5 m/s, E = 5 MPa), haptic tool penetration: " +
          ", ".join(f"{what} {1e3 * depth:.3f} mm" for what, depth in press)]
# block_press_friction as is (three rows per contact, the default reach): its models, and the
# device force of lcp beside coupling and linear against its reference (~4 min of the run).
bench.progress("block_press_friction")
m = models(FRICTION, "friction")
_, _, reference = bench.sim(FRICTION, "friction_reference", "--mode", "reference")
rms = ", ".join(f"{mode} {rms_vs(FRICTION, 'friction', mode, reference):.4f} N"
                for mode in ("lcp", "coupling", "linear"))
lines += ["", f"block_press_friction: rows {m['rows']} at peak ({m['coupled']} coupled), model "
          f"{m['peak_kB']:.1f} / {m['median_kB']:.1f} kB peak / median; RMS vs reference: {rms}"]
with open(bench.path("rows.md"), "w") as f:
    f.write("\n".join(lines) + "\n")
print("\n".join(lines))
PY
