#!/usr/bin/python3
"""The before/after tables of scripts/bench_speed.sh, from its outputs.

Usage: scripts/bench/speed_table.py OUT_DIR BASE_REV AFTER_REV

OUT_DIR holds before/ and after/ (each: fem/fem_bench.json, fem_step.json, friction.json and the
`hapsim sim` folders) and reference/ (block_press at 1 kHz). Prints Markdown and writes
OUT_DIR/speed.json. Medians of the frames with at least the issue's contact count; device-force
differences are RMS over every haptic step of |F − F_other| (3-D).
"""
import csv
import json
import os
import platform
import statistics
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from compare_modes import errors, read_forces  # noqa: E402

RUNS = ("before", "after")


def fem_rows(out, run):
    with open(os.path.join(out, run, "fem", "fem_bench.json")) as f:
        rows = json.load(f)["rows"]
    return {r["scene"]: r for r in rows if r["solver"] == "cg+lagged_cholesky"}


def benchmark_medians(path):
    """name (without _median) -> (median real time in the benchmark's unit, counters)."""
    with open(path) as f:
        data = json.load(f)
    return {b["run_name"]: b for b in data["benchmarks"] if b.get("aggregate_name") == "median"}


def frame_medians(folder, min_contacts):
    with open(os.path.join(folder, "frames.csv")) as f:
        rows = [r for r in csv.DictReader(f) if int(r["contacts"]) >= min_contacts]
    if not rows:
        return None
    med = lambda key: statistics.median(float(r[key]) for r in rows)  # noqa: E731
    return {"frames": len(rows), "max_contacts": max(int(r["contacts"]) for r in rows),
            "free_fem_ms": med("free_fem_ms"), "detection_ms": med("detection_ms"),
            "response_ms": med("response_ms"), "total_ms": med("total_ms")}


def ratio(before, after):
    return f"{before / after:.2f}x" if before and after else "–"


def fem_table(out):
    """FEM, 200 steps from rest, and the settled step; prints the table, returns its data."""
    fem = {run: fem_rows(out, run) for run in RUNS}
    step = {run: benchmark_medians(os.path.join(out, run, "fem_step.json")) for run in RUNS}
    print("| FEM (CG + lagged Cholesky) | before | after | speed-up | probe vs CHOLMOD, after "
          "(before) |")
    print("|---|---|---|---|---|")
    data = {}
    for scene, block in (("block_small", 1), ("block_large", 2)):
        b, a = fem["before"][scene], fem["after"][scene]
        accuracy = lambda r: r["probe_trajectory_difference_from_cholmod_m"] / r[  # noqa: E731
            "max_probe_displacement_m"]
        name = f"BM_ImplicitStep/block:{block}/cholmod:0"
        settled = [step[run][name]["real_time"] for run in RUNS]
        print(f"| {a['num_tets']:,} tets, mean of 200 steps from rest | {b['mean_ms']:.2f} ms | "
              f"{a['mean_ms']:.2f} ms | {ratio(b['mean_ms'], a['mean_ms'])} | "
              f"{accuracy(a):.1e} ({accuracy(b):.1e}) |")
        print(f"| {a['num_tets']:,} tets, median of those | {b['median_ms']:.2f} ms | "
              f"{a['median_ms']:.2f} ms | {ratio(b['median_ms'], a['median_ms'])} | |")
        print(f"| {a['num_tets']:,} tets, settled step (fem_step_benchmark) | {settled[0]:.2f} ms | "
              f"{settled[1]:.2f} ms | {ratio(*settled)} | |")
        data[scene] = {"before": b, "after": a, "settled_ms": settled}
    return data


def frame_table(out):
    """Visual frames and device forces; prints the table, returns its data."""
    _, f_ref = read_forces(os.path.join(out, "reference"))
    print("\n| scene, frames with ≥ N contacts | before: frame (free FEM / response) | after | "
          "speed-up | frame ÷ free FEM, after (before) | device force RMS: after vs before | "
          "vs the 1 kHz reference, after (before) |")
    print("|---|---|---|---|---|---|---|")
    data = {}
    # block_press_friction over every frame: issue 25 states its target as the median frame.
    for scene, min_contacts in (("block_press", 200), ("block_press_hybrid", 200),
                                ("block_press_large", 300), ("block_press_friction", 0)):
        if not all(os.path.isdir(os.path.join(out, run, scene)) for run in RUNS):
            continue  # a case this run left out (CASES)
        m = {run: frame_medians(os.path.join(out, run, scene), min_contacts) for run in RUNS}
        forces = {run: read_forces(os.path.join(out, run, scene))[1] for run in RUNS}
        between = errors(forces["after"], forces["before"])["rms_N"]
        vs_ref = "–"
        if scene in ("block_press", "block_press_hybrid"):
            vs_ref = (f"{errors(forces['after'], f_ref)['rms_N']:.4f} N "
                      f"({errors(forces['before'], f_ref)['rms_N']:.4f} N)")
        cell = lambda r: (f"{r['total_ms']:.2f} ms ({r['free_fem_ms']:.2f} / "  # noqa: E731
                          f"{r['response_ms']:.2f})")
        per_fem = lambda r: r["total_ms"] / r["free_fem_ms"]  # noqa: E731
        print(f"| {scene}, ≥ {min_contacts} ({m['after']['frames']} frames, up to "
              f"{m['after']['max_contacts']}) | {cell(m['before'])} | {cell(m['after'])} | "
              f"{ratio(m['before']['total_ms'], m['after']['total_ms'])} | "
              f"{per_fem(m['after']):.2f} ({per_fem(m['before']):.2f}) | {between:.2e} N | "
              f"{vs_ref} |")
        data[scene] = {"medians": m, "force_rms_after_vs_before_N": between}
    return data


def friction_table(out):
    """The warm friction step at 200 contacts; prints the table, returns its data."""
    friction = {run: benchmark_medians(os.path.join(out, run, "friction.json")) for run in RUNS}
    print("\n| warm friction step, 200 contacts (600 rows) | before | after | speed-up | "
          "Coulomb residual left, after |")
    print("|---|---|---|---|---|")
    data = {}
    for sweeps in (1, 2, 5):
        name = f"BM_HapticFrictionWarm/200/{sweeps}"
        t = [friction[run][name]["real_time"] if name in friction[run] else None for run in RUNS]
        fmt = lambda v: f"{v:.0f} µs" if v else "–"  # noqa: E731
        residual = friction["after"][name].get("residual", float("nan"))
        print(f"| {sweeps} sweep{'s' if sweeps > 1 else ''} a step | {fmt(t[0])} | {fmt(t[1])} | "
              f"{ratio(t[0], t[1])} | {residual:.1e} |")
        data[sweeps] = t
    return data


def main(out, base_rev, after_rev):
    result = {"base_rev": base_rev, "after_rev": after_rev,
              "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
              "machine": platform.processor() or platform.machine()}
    print(f"Before: {base_rev}; after: {after_rev} (the tree built when the run began). "
          f"Tables written {result['date']}.\n")
    # Each table only if this run measured its cases (scripts/bench_speed.sh's CASES).
    have = lambda *parts: all(os.path.exists(os.path.join(out, run, *parts))  # noqa: E731
                              for run in RUNS)
    if have("fem", "fem_bench.json") and have("fem_step.json"):
        result["fem"] = fem_table(out)
    if os.path.exists(os.path.join(out, "reference", "haptic.csv")):
        result["frames"] = frame_table(out)
    if have("friction.json"):
        result["friction"] = friction_table(out)
    tmp = os.path.join(out, "speed.json.tmp")
    with open(tmp, "w") as f:
        json.dump(result, f, indent=1)
    os.replace(tmp, os.path.join(out, "speed.json"))


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], sys.argv[3])
