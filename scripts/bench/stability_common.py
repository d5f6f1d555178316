"""What the stability maps (stability.py) share: the pressed scene, the map colours, and helpers to
read a run (JSON-safe floats, the haptic log) and to draw a map of cells on log axes.
"""
import math
import os

import numpy as np
import yaml
from matplotlib.patches import Rectangle

from common import REPO, read_csv

PRESS = "scenes/block_press.yaml"
STABLE_COLOR, FAIL_COLOR = "#cfe8cf", "#f4b6b6"


def finite(x):
    """A float for JSON, or None when undefined (NaN, inf, missing)."""
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else None


def press_scene():
    with open(os.path.join(REPO, PRESS)) as f:
        return yaml.safe_load(f)


def haptic(folder):
    rows = read_csv(os.path.join(folder, "haptic.csv"))
    return {key: np.array([r[key] for r in rows]) for key in rows[0]}


def edges(values):
    """Cell edges (geometric) around each of the sorted unique values."""
    values = sorted(set(values))
    if len(values) == 1:
        return {values[0]: (values[0] / 1.5, values[0] * 1.5)}
    mids = [math.sqrt(a * b) for a, b in zip(values, values[1:])]
    lows = [values[0] ** 2 / mids[0]] + mids
    highs = mids + [values[-1] ** 2 / mids[-1]]
    return {v: (lo, hi) for v, lo, hi in zip(values, lows, highs)}


def cell_map(axis, points, xkey, ykey, failed, label, mark=None):
    """A cell per point on log axes, red where failed(point), annotated with label(point)."""
    xe, ye = edges([p[xkey] for p in points]), edges([p[ykey] for p in points])
    for p in points:
        (x0, x1), (y0, y1) = xe[p[xkey]], ye[p[ykey]]
        axis.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, ec="white", lw=1.5,
                                 fc=FAIL_COLOR if failed(p) else STABLE_COLOR))
        text = label(p) + (f"\n{mark(p)}" if mark and mark(p) else "")
        axis.text(p[xkey], p[ykey], text, ha="center", va="center", fontsize=7)
    axis.set(xscale="log", yscale="log", xlim=(min(v[0] for v in xe.values()),
                                                max(v[1] for v in xe.values())),
             ylim=(min(v[0] for v in ye.values()), max(v[1] for v in ye.values())))
    axis.set_xticks(sorted(xe))
    axis.set_xticklabels([f"{v:g}" for v in sorted(xe)])
    axis.set_yticks(sorted(ye))
    axis.set_yticklabels([f"{v:g}" for v in sorted(ye)])
    axis.minorticks_off()
