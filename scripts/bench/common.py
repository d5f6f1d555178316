"""What every experiment of scripts/bench.sh shares: running hapsim, scene variants, progress,
CSV reading, the Pareto front and chart saving.

An experiment is a module with `run(bench) -> dict`; the dict holds its results (plain JSON), a
"figures" list of {"file", "caption"} (PNG files written into bench.out_dir) and "markdown", the
lines RESULTS.md shows under the experiment's title. Nothing here knows about one experiment.
"""
import copy
import csv
import json
import math
import os
import platform
import subprocess
import sys
import time

import yaml

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402,F401  (experiments take plt from here)
import matplotlib.text  # noqa: E402  (place_labels measures a text without its line)
import matplotlib.ticker  # noqa: E402

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
        return self.run_program(self.hapsim, *args)

    def run_program(self, program, *args):
        """Runs `PROGRAM ARGS...` from the repository root; its stdout, or BenchError with the
        command and its stderr's tail."""
        command = [program] + [str(a) for a in args]
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


def rate_text(hz):
    """A rate as charts and tables print it: 3 significant digits (33.3 Hz, not 33.3333), in
    plain notation (1000 Hz, not 1e+03)."""
    return f"{float(f'{hz:.3g}'):g} Hz"


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


# Where a point's label may go, in points from the point, tried in this order: beside it up and
# right first, then the other corners, then further out.
LABEL_OFFSETS = [(4, 3, "left", "bottom"), (4, -3, "left", "top"), (-4, 3, "right", "bottom"),
                 (-4, -3, "right", "top"), (4, 11, "left", "bottom"), (4, -11, "left", "top"),
                 (-4, 11, "right", "bottom"), (-4, -11, "right", "top"),
                 (10, 0, "left", "center"), (-10, 0, "right", "center"),
                 (4, 19, "left", "bottom"), (4, -19, "left", "top"),
                 (-4, 19, "right", "bottom"), (-4, -19, "right", "top")]
# Where a label that must be drawn finds none of those free: farther out, with a thin line to its
# point (rings of 26, 38 and 52 points, twelve directions each).
LEADER_OFFSETS = [(round(r * math.cos(math.radians(a))), round(r * math.sin(math.radians(a))),
                   "left" if math.cos(math.radians(a)) > 0.1 else
                   "right" if math.cos(math.radians(a)) < -0.1 else "center",
                   "bottom" if math.sin(math.radians(a)) > 0.1 else
                   "top" if math.sin(math.radians(a)) < -0.1 else "center")
                  for r in (26, 38, 52) for a in range(15, 360, 30)]


def place_labels(axis, labels, fontsize=7, avoid=()):
    """Annotates each (x, y, text, color[, optional]) beside its point, at the first of
    LABEL_OFFSETS where it stays inside the axes and overlaps nothing placed before it: no label
    (in any panel of the figure), no text on the axis ("finest", a line's name), not its legend,
    no marker of the points labelled (a 5-point square around each) and no (x, y, radius in
    points) of `avoid` (a ring drawn around a point). Where none is free, a label that must be
    drawn goes farther out with a line to its point (LEADER_OFFSETS), else at the first offset;
    an optional one (draw_pareto's off the front: the tables name every point) is left out. Call
    once every panel of the figure is set up: placement is measured in the figure's pixels, and the first
    call fixes the layout. The required labels are placed first, then the optional ones, each in
    the order given, so put the ones that matter most first."""
    fig = axis.figure
    if not hasattr(fig, "_hapsim_label_boxes"):
        # The final layout, once per figure: the labels are kept out of it (set_in_layout), so
        # save_figure's tight_layout then moves nothing and the measured boxes stay true.
        fig.tight_layout()
        fig._hapsim_label_boxes = []
    taken = fig._hapsim_label_boxes
    renderer = fig.canvas.get_renderer()
    taken += [tuple(text.get_window_extent(renderer).extents) for text in axis.texts]
    if axis.get_legend() is not None:
        taken.append(tuple(axis.get_legend().get_window_extent(renderer).extents))
    inside = axis.get_window_extent(renderer).extents
    to_pixels = axis.transData.transform
    points_to_pixels = fig.dpi / 72.0

    def square(x, y, radius_pt):
        px, py = to_pixels((x, y))
        r = radius_pt * points_to_pixels
        return (px - r, py - r, px + r, py + r)

    markers = [square(label[0], label[1], 5) for label in labels] + [square(*a) for a in avoid]

    def overlaps(a, b):
        return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]

    def optional(i):
        return len(labels[i]) > 4 and labels[i][4]

    def is_free(box, i):
        return (inside[0] <= box[0] and box[2] <= inside[2] and inside[1] <= box[1]
                and box[3] <= inside[3]
                and not any(overlaps(box, other) for other in taken)
                and not any(overlaps(box, m) for j, m in enumerate(markers) if j != i))

    for i in sorted(range(len(labels)), key=optional):
        x, y, text, color = labels[i][:4]
        if not text:
            continue
        chosen = None
        offsets = LABEL_OFFSETS + ([] if optional(i) else LEADER_OFFSETS)
        for k, (dx, dy, ha, va) in enumerate(offsets):
            leader = k >= len(LABEL_OFFSETS)
            note = axis.annotate(text, (x, y), textcoords="offset points", xytext=(dx, dy),
                                 ha=ha, va=va, fontsize=fontsize, color=color,
                                 arrowprops=dict(arrowstyle="-", color=color, lw=0.5,
                                                 shrinkA=0, shrinkB=3) if leader else None)
            note.set_in_layout(False)
            # The text's own box: an annotation's extent takes in its line too, so the text's is
            # taken once the annotation has placed it.
            note.update_positions(renderer)
            box = tuple(matplotlib.text.Text.get_window_extent(note, renderer).extents)
            free = is_free(box, i)
            if free or (chosen is None and not optional(i) and not leader):
                if chosen is not None:
                    chosen[0].remove()
                chosen = (note, box)
                if free:
                    break
            else:
                note.remove()
        if chosen is not None:
            taken.append(chosen[1])


def draw_pareto(axis, points, labels, color="k", marker="o", name=None):
    """Each point labelled (place_labels, once the caller has set the scales; the labels of the
    points off the front only where there is room), the front drawn as a step line through the
    undominated points, by the error's size (a signed error below zero is no better for it).
    Returns the labels to place."""
    xs = [p[0] for p in points]
    ys = [p[1] for p in points]
    axis.scatter(xs, ys, color=color, marker=marker, zorder=3, label=name)
    front = pareto_front([(x, abs(y)) for x, y in points])
    if len(front) > 1:
        axis.step([xs[i] for i in front], [ys[i] for i in front], where="post", color=color,
                  alpha=0.4, lw=1)
    return [(x, y, label, color, i not in front)
            for i, (x, y, label) in enumerate(zip(xs, ys, labels))]


def label_log_x(axis):
    """Plain numbers on a log x axis, and its minor ticks at 2 and 5 labelled too: on an axis
    spanning about a decade, matplotlib's default labels a single tick (10⁰), and the reader can
    read no cost off it."""
    def minor(value, _):
        mantissa = value / 10 ** math.floor(math.log10(value))
        return f"{value:g}" if round(mantissa) in (2, 5) else ""
    axis.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
    axis.xaxis.set_minor_formatter(matplotlib.ticker.FuncFormatter(minor))


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
