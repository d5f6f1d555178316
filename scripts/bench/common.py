"""What every experiment of scripts/bench.sh shares: running hapsim, scene variants, progress,
CSV reading, the Pareto front and chart saving.

An experiment is a module with `run(bench) -> dict`; the dict holds its results (plain JSON), a
"figures" list of {"file", "caption"} (PNG files written into bench.out_dir) and "markdown", the
lines RESULTS.md shows under the experiment's title. Nothing here knows about one experiment.
"""
import copy
import csv
import json
import os
import platform
import subprocess
import sys
import time

import yaml

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402,F401  (experiments take plt from here)

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


class BenchError(RuntimeError):
    pass


class Bench:
    def __init__(self, hapsim, out_dir, quick):
        self.hapsim = hapsim
        self.out_dir = out_dir
        self.quick = quick
        self.start = time.monotonic()
        os.makedirs(out_dir, exist_ok=True)

    def progress(self, message):
        """One line per run: elapsed wall time and what runs now (the whole bench takes minutes)."""
        print(f"bench [{time.monotonic() - self.start:7.1f} s] {message}", flush=True)

    def path(self, *parts):
        path = os.path.join(self.out_dir, *parts)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        return path

    def hapsim_run(self, *args):
        """Runs `hapsim ARGS...`; a failure raises with the command and its stderr's tail."""
        command = [self.hapsim] + [str(a) for a in args]
        done = subprocess.run(command, cwd=REPO, capture_output=True, text=True)
        if done.returncode != 0:
            tail = "\n".join(done.stderr.strip().splitlines()[-5:])
            raise BenchError(f"{' '.join(command)} exited with {done.returncode}:\n{tail}")
        return done.stdout

    def scene_variant(self, base_scene, edits, name):
        """Writes base_scene (a path under scenes/) with `edits` applied as OUT/scenes/NAME.yaml.

        edits: {"body.mesh.box.cells": [20, 20, 10], ...}: dotted keys into the YAML mappings.
        A key that the base scene does not have is an error (a typo would otherwise go unseen),
        unless its parent mapping exists (a new optional key)."""
        with open(os.path.join(REPO, base_scene)) as f:
            scene = yaml.safe_load(f)
        scene = copy.deepcopy(scene)
        for dotted, value in edits.items():
            keys = dotted.split(".")
            node = scene
            for key in keys[:-1]:
                if not isinstance(node, dict) or key not in node:
                    raise BenchError(f"{base_scene}: no mapping '{key}' for edit '{dotted}'")
                node = node[key]
            node[keys[-1]] = value
        scene["name"] = name
        path = self.path("scenes", name + ".yaml")
        with open(path + ".tmp", "w") as f:
            f.write(f"# {base_scene} with {json.dumps(edits)} (scripts/bench)\n")
            yaml.safe_dump(scene, f, sort_keys=False)
        os.replace(path + ".tmp", path)
        return path

    def sim(self, scene_path, out_name, *options):
        """`hapsim sim` into OUT/runs/OUT_NAME; returns (summary dict, frames rows, haptic folder)."""
        out = self.path("runs", out_name, "summary.json")
        folder = os.path.dirname(out)
        self.hapsim_run("sim", scene_path, "--out", folder, *options)
        with open(out) as f:
            summary = json.load(f)
        return summary, read_csv(os.path.join(folder, "frames.csv")), folder


def read_csv(path):
    with open(path) as f:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]


def median(values):
    values = sorted(values)
    n = len(values)
    if n == 0:
        return float("nan")
    return values[n // 2] if n % 2 else 0.5 * (values[n // 2 - 1] + values[n // 2])


def pareto_front(points):
    """Indices of the points (cost, error) no other point beats in both, by increasing cost."""
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front, best = [], float("inf")
    for i in order:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


def draw_pareto(axis, points, labels, color="k", marker="o", name=None):
    """Each point labelled, the front drawn as a step line through the undominated points."""
    xs = [p[0] for p in points]
    ys = [p[1] for p in points]
    axis.scatter(xs, ys, color=color, marker=marker, zorder=3, label=name)
    for x, y, label in zip(xs, ys, labels):
        axis.annotate(label, (x, y), textcoords="offset points", xytext=(4, 4), fontsize=7)
    front = pareto_front(points)
    if len(front) > 1:
        axis.step([xs[i] for i in front], [ys[i] for i in front], where="post", color=color,
                  alpha=0.4, lw=1)


def save_figure(fig, path):
    """PNG written under a temporary name and renamed: never a half-written chart."""
    fig.tight_layout()
    fig.savefig(path + ".tmp.png", dpi=110)
    os.replace(path + ".tmp.png", path)
    plt.close(fig)


def machine():
    model = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{model}, {os.cpu_count()} logical cores, {platform.system()} {platform.release()}"


def fail(message):
    print(f"bench: {message}", file=sys.stderr)
    sys.exit(1)
