"""The cantilever over mesh resolution and lattice orientation, linear against corotational
(issue 12): the tip deflection against beam theory, with the step's cost beside it.

Scene: scenes/cantilever.yaml, a 0.5 m beam of 5 x 5 cm square section (E 1e7 Pa, ν 0.3,
ρ 1000 kg/m³) clamped over its whole face at x = 0, under its own weight; the probe is the tip's
centre node (x = L, y = z = 0), on the neutral axis. Each run is `hapsim fem` (implicit Euler, the
scene's 300 steps of 1/60 s from rest); the dynamics settle to the static equilibrium, which is what
is compared (the last 10 % of the steps are checked to be settled). The load is gravity scaled in
the variant; the references, their equations and sources are in beam_theory.py.

(a) Small load, g = 0.981 m/s² (δ/L ≈ 0.7 %): against linear beam theory with the shear term,
        δ = q L⁴ / (8 E I)  +  q L² / (2 κ G A)
    (Euler–Bernoulli and Timoshenko's shear deflection). The error is |u_z − δ| / δ (the axial
    displacement is second order; reported, not scored).
(b) Large load, g = 5 × 9.81 m/s² (δ/L ≈ 34 %): against the elastica of a cantilever under its own
    weight as a dead load, with the same Timoshenko shear and the axial stretch (the plain
    inextensible elastica is reported beside it). The error of (b) is |u_FEM − u_ref| / |u_ref|
    over the axial and the vertical component; each is also reported alone (linear FEM has no
    axial shortening at all).

Lattice orientation: the box lattice cuts every cube into five tets, alternating with the parity of
i + j + k. That pattern is invariant under every permutation of the axes (and, with even cell
counts, under reflections), so a beam built along y (load −z) or along z (load −x) is the mirror
image of the one along x, mesh included: those runs check that nothing in the code prefers an
axis (they agree to the solver's tolerance). Gravity along the section's diagonal, (0, −1, −1)/√2,
bends the beam the same way (a square section's second moment is the same about every centroidal
axis) but across the cells diagonally; for linear elasticity that is again exact by symmetry (the
superposition of two mirror images), for corotational elasticity the difference is the lattice's
anisotropy under large rotations. The one mesh difference left to an axis-aligned beam is the
cut's phase at the clamp: with an odd number of cells along the beam, the beam along −x (clamped at
x = 0, tip at x = −L) starts with the other cut than the beam along +x on the same lattice
("reversed" against "x" on (n + 1) × m × m). A beam oblique to the lattice would need a mesh the
box lattice cannot make.

The page's text is written by cantilever_report.py.
"""
import csv
import json
import math
import os
import time

from matplotlib.ticker import FuncFormatter

from beam_theory import H_M, L_M, LOADS, references
from cantilever_report import is_base, markdown, mesh_label, quadratic_markdown
from common import REPO, BenchError, draw_pareto, plt, save_figure

SCENE = "scenes/cantilever.yaml"
BEAM_SURFACE = "scenes/meshes/beam.obj"  # the same beam as a closed surface
ELASTICITIES = ["linear", "corotational"]
COLORS = {"linear": "C0", "corotational": "C3"}
P2_COLOR = "C2"
# name: (beam axis, its direction ±1 from the clamp at 0, unit load direction, legend).
# "x" is the scene as written; "reversed" runs only with an odd cell count along the beam (with an
# even one it is the mirror image of "x"), compared with "x" on the same odd lattice.
ORIENTATIONS = {
    "x": (0, 1, (0.0, 0.0, -1.0), "beam along x"),
    "y": (1, 1, (0.0, 0.0, -1.0), "beam along y, load −z"),
    "z": (2, 1, (-1.0, 0.0, 0.0), "beam along z, load −x"),
    "diag": (0, 1, (0.0, -math.sqrt(0.5), -math.sqrt(0.5)), "load along the section diagonal"),
    "reversed": (0, -1, (0.0, 0.0, -1.0), "odd n, beam along −x"),
}
MARKERS = {"x": "o", "y": "x", "z": "+", "diag": "D", "reversed": "<"}


# ---------------------------------------------------------------------------- the runs

def plan(quick):
    """(base meshes: cells along the beam n, the lattice n × n/10 × n/10; orientation meshes: the
    y, z and diag variants on n × n/10 × n/10, and x against reversed on (n + 1) × n/10 × n/10)."""
    if quick:
        return [20, 40], [20]
    return [20, 40, 60, 80, 120], [20, 40, 80]


def quadratic_plan(quick):
    """Cells along the beam of the quadratic element's lattices (n × n/10 × n/10, down to 1), and
    the cell sizes of the unstructured meshes both elements run on (issue 27's third target)."""
    if quick:
        return [10, 20], [0.025]
    return [10, 20, 30, 40], [0.025, 0.0167, 0.0125]


def variant_edits(n, m, orientation, elasticity, g, element="p1"):
    """Scene edits: n cells along the beam, m (even: the tip's centre is a node; with quadratic
    tets an edge node is one too) across."""
    axis, sign, load, _ = ORIENTATIONS[orientation]
    lo, hi, cells = [-0.5 * H_M] * 3, [0.5 * H_M] * 3, [m] * 3
    fixed_lo, fixed_hi, probe = [-0.03] * 3, [0.03] * 3, [0.0] * 3
    lo[axis], hi[axis], cells[axis] = min(0.0, sign * L_M), max(0.0, sign * L_M), n
    fixed_lo[axis], fixed_hi[axis], probe[axis] = -0.001, 0.001, sign * L_M
    return {"gravity_m_s2": [round(g * c, 12) + 0.0 for c in load],
            "body.mesh.box": {"min_m": lo, "max_m": hi, "cells": cells},
            "body.elasticity": elasticity, "body.element": element,
            "body.fixed": {"min_m": fixed_lo, "max_m": fixed_hi},
            "body.probes": [{"name": "tip_center", "position_m": probe}]}


def components(u, orientation):
    """(axial, along the load, lateral magnitude) of a displacement."""
    axis, sign, load, _ = ORIENTATIONS[orientation]
    axial = sign * u[axis]
    along = sum(a * b for a, b in zip(u, load))
    rest = [(0.0 if i == axis else u[i]) - along * load[i] for i in range(3)]
    return axial, along, math.sqrt(sum(r * r for r in rest))


def settling(folder):
    """Largest distance of the tip over the last 10 % of the steps from its final position,
    relative to the final displacement: small means the dynamics reached the static state."""
    with open(os.path.join(folder, "steps.csv")) as f:
        rows = list(csv.DictReader(f))
    tip = [[float(r[f"tip_center_u{c}_m"]) for c in "xyz"] for r in rows]
    final = tip[-1]
    size = math.sqrt(sum(c * c for c in final))
    tail = tip[len(tip) - max(1, len(tip) // 10):]
    return max(math.dist(t, final) for t in tail) / size


def fem_run(bench, n, m, orientation, elasticity, load, refs, element="p1", cell_size_m=None):
    """One settled run. cell_size_m: the beam's closed surface (scenes/meshes/beam.obj) filled
    with unstructured tets of that size by Gmsh instead of the n × m × m lattice (n, m: 0)."""
    label = f"cantilever_{load}_{orientation}_{n}x{m}_{elasticity}" + (
        "" if element == "p1" else f"_{element}")
    edits = variant_edits(n or 1, m or 1, orientation, elasticity, LOADS[load]["g"], element)
    if cell_size_m is not None:
        label = f"cantilever_{load}_unstructured_{1e3 * cell_size_m:g}mm_{elasticity}_{element}"
        edits["body.mesh"] = {"surface": os.path.join(REPO, BEAM_SURFACE),
                              "cell_size_m": cell_size_m}
    scene = bench.scene_variant(SCENE, edits, label)
    folder = os.path.dirname(bench.path("runs", label, "summary.json"))
    bench.progress(f"cantilever: {load} load, {orientation}, {elasticity}, {element}, "
                   + (f"{n}×{m}×{m} ({5 * n * m * m} tets)" if cell_size_m is None else
                      f"unstructured, {1e3 * cell_size_m:g} mm"))
    bench.hapsim_run("fem", scene, "--out", folder)
    with open(os.path.join(folder, "summary.json")) as f:
        summary = json.load(f)
    probe = summary["probes"][0]
    if probe["name"] != "tip_center":
        raise BenchError(f"{label}: first probe is {probe['name']}")
    u = probe["final_displacement_m"]
    axial, along, lateral = components(u, orientation)
    ref_axial, ref_vertical = refs[load]["tip_m"]
    ref_along = -ref_vertical
    vertical_error = along / ref_along - 1.0
    axial_error = axial / ref_axial - 1.0
    if load == "small":
        error = abs(vertical_error)
    else:
        error = math.hypot(axial - ref_axial, along - ref_along) / math.hypot(ref_axial, ref_along)
    return {"load": load, "orientation": orientation, "elasticity": elasticity, "element": element,
            "cells": edits["body.mesh.box"]["cells"] if cell_size_m is None else None, "n": n,
            "m": m, "cell_size_m": cell_size_m, "tets": summary["num_tets"],
            "nodes": summary["num_nodes"], "steps": summary["num_steps"],
            "mean_ms": summary["timings"]["total"]["mean_ms"],
            "median_ms": summary["timings"]["total"]["median_ms"],
            "tip_displacement_m": u, "tip_axial_m": axial, "tip_along_load_m": along,
            "tip_lateral_m": lateral, "reference_axial_m": ref_axial,
            "reference_along_load_m": ref_along, "vertical_error": vertical_error,
            "axial_error": axial_error, "relative_error": error,
            "settling": settling(folder)}


def richardson(runs):
    """Limit of the along-load tip over the three finest meshes, f(h) = f0 + C h^p (h ∝ 1/n),
    p fitted; None when the three are not monotone."""
    runs = sorted(runs, key=lambda r: r["n"])[-3:]
    if len(runs) < 3:
        return None
    h = [1.0 / r["n"] for r in runs]
    f = [r["tip_along_load_m"] for r in runs]
    ratio = (f[0] - f[1]) / (f[1] - f[2]) if f[1] != f[2] else float("nan")
    if not ratio > 0.0:
        return None

    def g(p):
        return (h[0] ** p - h[1] ** p) / (h[1] ** p - h[2] ** p) - ratio

    lo, hi = 0.3, 6.0
    if g(lo) * g(hi) > 0.0:
        return None
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if g(lo) * g(mid) <= 0.0:
            hi = mid
        else:
            lo = mid
    p = 0.5 * (lo + hi)
    c = (f[1] - f[2]) / (h[1] ** p - h[2] ** p)
    return {"order": p, "limit_along_load_m": f[2] - c * h[2] ** p,
            "from_n": [r["n"] for r in runs]}


# ---------------------------------------------------------------------------- charts

def chart_pareto(bench, runs):
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    for axis, load in zip(axes, LOADS):
        for elasticity in ELASTICITIES:
            points = [r for r in runs if r["load"] == load and is_base(r)
                      and r["elasticity"] == elasticity]
            xy = [(r["mean_ms"], 100.0 * r["relative_error"]) for r in points]
            draw_pareto(axis, xy, [""] * len(points), color=COLORS[elasticity], name=elasticity)
            # labels placed by hand: at the small load both elasticities have the same error
            below = elasticity == "corotational"
            for (x, y), r in zip(xy, points):
                axis.annotate(mesh_label(r), (x, y), textcoords="offset points",
                              xytext=(5, -11) if below else (-5, 5), fontsize=7,
                              ha="left" if below else "right", color=COLORS[elasticity])
        quadratic = [r for r in runs if r["load"] == load and r["element"] == "p2"
                     and r["cell_size_m"] is None]
        if quadratic:
            xy = [(r["mean_ms"], 100.0 * r["relative_error"]) for r in quadratic]
            draw_pareto(axis, xy, [""] * len(xy), color=P2_COLOR, marker="s",
                        name="corotational, quadratic tets")
            for (x, y), r in zip(xy, quadratic):
                axis.annotate(mesh_label(r), (x, y), textcoords="offset points", xytext=(5, 5),
                              fontsize=7, color=P2_COLOR)
        axis.set(xscale="log", yscale="log", xlabel="mean FEM step (ms)",
                 ylabel="tip error against beam theory (%)",
                 title=f"{LOADS[load]['title']}\n(labels: lattice cells; lines: Pareto fronts)")
        axis.grid(True, which="both", alpha=0.3)
        axis.legend(fontsize=8)
        axis.margins(x=0.15, y=0.15)
        # plain numbers; the minor ticks 2, 3, 5 labelled too where the axis spans few decades
        for ticks, (low, high) in ((axis.xaxis, axis.get_xlim()), (axis.yaxis, axis.get_ylim())):
            ticks.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
            few = high / low < 50.0
            ticks.set_minor_formatter(FuncFormatter(
                lambda v, _, few=few: f"{v:g}" if few and f"{v:.1e}"[0] in "235" else ""))
    save_figure(fig, bench.path("cantilever_pareto.png"))
    return {"file": "cantilever_pareto.png",
            "caption": "Cantilever tip error against the mean FEM step, per lattice (beam along "
                       "x): "
                       "left the small load against Euler–Bernoulli + Timoshenko, right the large "
                       "load against the elastica (axial and vertical), linear and corotational, "
                       "and corotational on quadratic tets (squares), with each one's Pareto "
                       "front."}


def chart_convergence(bench, runs, refs):
    panels = [("small", "tip_along_load_m", "reference_along_load_m",
               "small load: vertical tip / reference"),
              ("large", "tip_along_load_m", "reference_along_load_m",
               "large load: vertical tip / reference"),
              ("large", "tip_axial_m", "reference_axial_m",
               "large load: axial tip (shortening) / reference")]
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
    for axis, (load, key, ref_key, title) in zip(axes, panels):
        for elasticity in ELASTICITIES:
            base = sorted((r for r in runs if r["load"] == load and is_base(r)
                           and r["elasticity"] == elasticity), key=lambda r: r["n"])
            axis.plot([r["n"] for r in base], [r[key] / r[ref_key] for r in base], "o-",
                      color=COLORS[elasticity], label=f"{elasticity} (beam along x)", ms=5)
            odd = [r for r in runs if r["load"] == load and r["orientation"] == "x"
                   and not is_base(r) and r["elasticity"] == elasticity and r["element"] == "p1"]
            axis.scatter([r["n"] for r in odd], [r[key] / r[ref_key] for r in odd], marker=">",
                         color=COLORS[elasticity], s=30, label=f"{elasticity}: odd n, beam along x",
                         zorder=3)
            for orientation, (_, _, _, legend) in ORIENTATIONS.items():
                if orientation == "x":
                    continue
                other = [r for r in runs if r["load"] == load and r["orientation"] == orientation
                         and r["elasticity"] == elasticity]
                style = ({"facecolors": "none", "edgecolors": COLORS[elasticity], "s": 40}
                         if MARKERS[orientation] in "D<"
                         else {"color": COLORS[elasticity], "s": 50})
                axis.scatter([r["n"] for r in other], [r[key] / r[ref_key] for r in other],
                             marker=MARKERS[orientation], label=f"{elasticity}: {legend}",
                             zorder=3, **style)
        axis.axhline(1.0, color="k", lw=1.5, label="reference")
        axis.set(xscale="log", xlabel="cells along the beam (lattice n × n/10 × n/10)",
                 ylabel="FEM / reference", title=title)
        ticks = sorted({r["n"] for r in runs if is_base(r)})
        axis.set_xticks(ticks)
        axis.set_xticklabels([str(n) for n in ticks])
        axis.minorticks_off()
        axis.grid(True, alpha=0.3)
    axes[-1].legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=7, borderaxespad=0)
    save_figure(fig, bench.path("cantilever_convergence.png"))
    return {"file": "cantilever_convergence.png",
            "caption": "Cantilever tip over the lattice resolution, as a fraction of the "
                       "reference: the vertical deflection at both loads and the axial shortening "
                       "at the large load (linear FEM has none: 0). Lines: beam along x on cubic "
                       "cells; markers: the other orientations (mirror images of the lattice, the "
                       "load along the section's diagonal) and, on n + 1 cells along the beam, "
                       "the beam along +x and along −x (the cut's other phase at the clamp)."}


def run(bench):
    started = time.monotonic()
    refs = references()
    bench.progress("cantilever: references: small load "
                   f"{1e3 * refs['small']['tip_m'][1]:.4f} mm, large load tip "
                   f"({1e3 * refs['large']['tip_m'][0]:.2f}, {1e3 * refs['large']['tip_m'][1]:.2f})"
                   " mm")
    base_meshes, orientation_meshes = plan(bench.quick)
    runs = []
    for load in LOADS:
        for n in base_meshes:
            for elasticity in ELASTICITIES:
                runs.append(fem_run(bench, n, n // 10, "x", elasticity, load, refs))
        for n in orientation_meshes:
            for elasticity in ELASTICITIES:
                for orientation in ("y", "z", "diag"):
                    runs.append(fem_run(bench, n, n // 10, orientation, elasticity, load, refs))
                for orientation in ("x", "reversed"):
                    runs.append(fem_run(bench, n + 1, n // 10, orientation, elasticity, load,
                                        refs))
        lattices, cell_sizes = quadratic_plan(bench.quick)
        for n in lattices:
            runs.append(fem_run(bench, n, max(1, n // 10), "x", "corotational", load, refs, "p2"))
        for h in cell_sizes:
            for element in ("p1", "p2"):
                runs.append(fem_run(bench, 0, 0, "x", "corotational", load, refs, element, h))
    unsettled = [r for r in runs if r["settling"] > 1e-3]
    extrapolated = {}
    if len(base_meshes) >= 3:
        for load in LOADS:
            for elasticity in ELASTICITIES:
                e = richardson([r for r in runs if r["load"] == load and is_base(r)
                                and r["elasticity"] == elasticity])
                if e:
                    extrapolated[(load, elasticity)] = e
    wall_s = time.monotonic() - started
    output = {"scene": SCENE, "references": refs, "runs": runs,
              "extrapolated": [dict(load=k[0], elasticity=k[1], **v)
                               for k, v in extrapolated.items()],
              "unsettled_runs": [f"{r['load']} {r['orientation']} {mesh_label(r)} {r['elasticity']}"
                                 for r in unsettled],
              "wall_s": wall_s,
              "figures": [chart_pareto(bench, runs), chart_convergence(bench, runs, refs)]}
    output["markdown"] = markdown(runs, refs, extrapolated, wall_s) + quadratic_markdown(runs)
    if unsettled:
        output["markdown"].append("**Not settled** (the tip still moves by more than 0.1 % over "
                                  "the last 10 % of the steps): "
                                  + ", ".join(output["unsettled_runs"]) + ".")
        output["markdown"].append("")
    return output
