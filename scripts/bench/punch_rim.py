"""The flat punch on meshes graded towards its rim: linear against quadratic tets (issue 27).
Its meshing and press serve hertz_disk.py too (the sphere on meshes graded from its contact zone).

Under a rigid flat punch the pressure is singular at the rim, p ~ (a² − r²)^(−1/2) (Johnson,
Contact Mechanics, §3.7). On the lattices of the indentation experiment the cells are finest at the
punch's centre, not along its rim, and the error of either element is then that of the rim's cells.
Here the block of scenes/flat_punch.yaml is meshed by Gmsh (tests/bench/punch_block_mesh.cc) with
the rim circle in its top face, 0.1 % inside the punch's rim as the rim-following lattices have it
(indentation.py says why), and tets whose edge grows linearly from h_rim on the rim to h_far at
20 mm from it: the mesh a finite-element analyst would draw for this problem, unstructured. Nodes
only touch the punch (`contact.tool_features: false`), so the contact ends at the rim. The P2 runs
take the same meshes' kind, coarser; each element gets the sizes that put it near the frame costs
of the other's. The coefficient is fitted as the indentation experiment fits it and compared with
the same bonded-layer reference. A fine quadratic mesh (16k tets) tests that reference from one
side: a conforming mesh integrated exactly is stiffer than the block it discretises, so the block
is at most that much stiffer than the layer formula says, once the mesh's rim polygon (below) is
allowed for (the block's finite width, 20 a, is not in the formula either).

The quadratic meshes are pressed twice: as the linear mesh's edges' midpoints give them, and with
the node of each edge leaving the rim a quarter of the way along it (QUARTER_POINT_FRACTION,
fem/quarter_point_nodes.h), which puts the leading √ρ term of the field into the rim's elements;
on these meshes, whose cells stay finite at the rim, the error of plain elements is otherwise set by
the rim's cells. The linear element has no such nodes: its runs of the same meshes' kind are what
both are compared with. The fine quadratic mesh is pressed both ways too.
Hand runs chose the fraction (ν 0.45, 2026-11-29, P2 2/15): +9.45 % at 0.27, +9.29 % at 0.26,
+9.17 % at 0.251, against +15.8 % with the nodes at the midpoints; exactly at ¼ the element is
flat at its corner and refused. They also found the quarter-point meshes' error then set by the
far cells (2/12 +5.4 % at 1.4 ms, 2/10 +3.6 % at 2.1 ms, against 2/15's +9.3 % at 0.86 ms; all on
the 10-node rim below, about 3 % soft for it): the sweep keeps the plain meshes' sizes, so that
each pair differs by the nodes alone.

Every rim is a polygon of the mesh's rim nodes (`rim_nodes`), inscribed in the circle: n nodes
inscribe 1 − sin(2π/n)·n/2π less area, and a flat punch's stiffness is close to that of the
circle of its area (the usual approximation for a compact shape), which goes as the area's root:
a coarse rim is softer than the circle for that alone, by what the markdown gives per rim.
"""
import math
import os
import re

import yaml

import indentation
from common import REPO, BenchError, label_log_x, place_labels, plt, save_figure

GRADING_DISTANCE_M = 0.02
# (h_rim, h_far) per element: the full sweep, the quick one, and the fine mesh that checks the
# reference (full run, ν 0.45 only: a 150 ms frame).
# The dearest of each (P1 0.2/3.5: 38k tets, 30 ms a frame; P2 0.6/8) reach past the 10 ms budget:
# where P2's ratio to P1 crosses ⅓ at ν 0.45.
MESHES = {"p1": [(0.6e-3, 10e-3), (0.4e-3, 6.5e-3), (0.3e-3, 5e-3), (0.25e-3, 4e-3),
                 (0.2e-3, 3.5e-3)],
          "p2": [(2e-3, 15e-3), (1.5e-3, 15e-3), (1e-3, 12e-3), (0.75e-3, 10e-3), (0.6e-3, 10e-3),
                 (0.6e-3, 8e-3)]}
QUICK_MESHES = {"p1": [(0.6e-3, 10e-3)], "p2": [(2e-3, 15e-3)]}
CONVERGED = ("p2", 0.5e-3, 4e-3)
# Where the node of an edge leaving the rim sits on quarter-point meshes (the docstring).
QUARTER_POINT_FRACTION = 0.26
# What each case's mesh is graded from (punch_block_mesh): the punch's rim, nodes only, as above;
# the sphere's contact zone (hertz_disk.py), a disk of HERTZ_DISK_M, the tool's features on.
HERTZ_DISK_M = 3e-3
# Per case: its runs' and meshes' prefix, its runs' `variant` (indentation.VARIANT_TEXT),
# punch_block_mesh's grading arguments, and the edits beside mesh, ν and element. An unknown case
# is a KeyError.
GRADED_CASES = {
    "punch": ("punch_rim", "graded",
              ["--rim-radius-m", indentation.PUNCH_A_M * (1.0 - indentation.RIM_INSIDE)],
              {"contact.tool_features": False}),
    "hertz": ("hertz_disk", "disk", ["--rim-radius-m", HERTZ_DISK_M, "--from-disk"], {}),
}
# (bench's folder, case, h_rim, h_far, quarter): (mesh file, tets, rim nodes); each mesh made once
_MADE = {}


def make_mesh(bench, rim_m, far_m, name="punch", quarter=False):
    """The block's mesh file (OUT/meshes/), its tet count and its nodes on the rim circle, from
    punch_block_mesh, which the build puts beside `hapsim` (BUILD/apps/hapsim,
    BUILD/tests/punch_block_mesh). The block's corners are the case's scene's; name "punch" grades
    from the rim, "hertz" from the disk; quarter: quadratic, with quarter-point nodes at the rim."""
    prefix, _, grading, _ = GRADED_CASES[name]
    key = (bench.out_dir, name, rim_m, far_m, quarter)
    if key in _MADE:
        return _MADE[key]
    program = os.path.join(os.path.dirname(os.path.dirname(bench.hapsim)), "tests",
                           "punch_block_mesh")
    if not os.access(program, os.X_OK):
        raise BenchError(f"{program} is missing: the build makes it with the tests")
    with open(os.path.join(REPO, indentation.CASES[name]["scene"])) as f:
        box = yaml.safe_load(f)["body"]["mesh"]["box"]
    path = bench.path("meshes", f"{prefix}_{1e3 * rim_m:g}mm_{1e3 * far_m:g}mm"
                      + ("_quarter" if quarter else "") + ".msh")
    out = bench.run_program(program, "--min-m", *box["min_m"], "--max-m", *box["max_m"],
                            *grading, "--rim-cell-size-m", rim_m, "--cell-size-m", far_m,
                            "--grading-distance-m", GRADING_DISTANCE_M, "--out", path,
                            *(["--quarter-point-fraction", QUARTER_POINT_FRACTION] if quarter
                              else []))
    counts = {what: int(re.search(rf"^{what} (\d+)$", out, re.MULTILINE).group(1))
              for what in ("tets", "rim_nodes")}  # Gmsh's own lines may come first
    _MADE[key] = (path, counts["tets"], counts["rim_nodes"])
    return _MADE[key]


def press(bench, element, rim_m, far_m, nu, name="punch", quarter=False):
    """One press on the graded mesh (h_rim, h_far) in `element` at ν: the punch nodes only, the
    sphere as its scene has it; its fit and errors as indentation.press gives them. quarter: the
    quadratic mesh with quarter-point nodes at the rim (variant "quarter")."""
    case = indentation.CASES[name]
    prefix, variant, _, contact_edits = GRADED_CASES[name]
    if quarter:
        if element != "p2" or name != "punch":
            raise BenchError("quarter-point nodes are for the punch's quadratic meshes")
        variant = "quarter"
    label = (f"{prefix}_{element}_{1e3 * rim_m:g}mm_{1e3 * far_m:g}mm"
             + ("_quarter" if quarter else "") + f"_nu{nu:g}")
    bench.progress(f"{prefix}: {label}")
    mesh_path, tets, rim_nodes = make_mesh(bench, rim_m, far_m, name, quarter)
    edits = {"body.mesh": {"file": mesh_path}, "body.material.poisson_ratio": nu,
             "body.element": element, **contact_edits}
    summary, frames, _ = bench.sim(bench.scene_variant(case["scene"], edits, label), label)
    figures = indentation.score(summary, frames, name, case, nu)
    figures.pop("curve")
    # near_cell_m: the edge on the rim (punch) or the disk (sphere).
    # rim_nodes: the punch's rim polygon (a sphere's mesh has its disk's edge there, no rim).
    return {"element": element, "variant": variant, "near_cell_m": rim_m, "far_cell_m": far_m,
            "tets": tets, **({"rim_nodes": rim_nodes} if name == "punch" else {}),
            "poisson_ratio": nu, **figures}


def label_of(r):
    return (f"{r['element'].upper()}{'q' if r['variant'] == 'quarter' else ''} "
            f"{1e3 * r['near_cell_m']:g}/{1e3 * r['far_cell_m']:g}")


def table_markdown(runs, nus, where="rim"):
    md = [f"| element, edge on the {where} / far (mm) | tets | "
          + " | ".join(f"ν {nu:g}: frame, error (half-space / bonded layer)" for nu in nus) + " |",
          "|---|---:|" + "---:|" * len(nus)]
    keys = []
    for r in runs:
        key = (r["element"], r["variant"], r["near_cell_m"], r["far_cell_m"])
        if key not in keys:
            keys.append(key)
    for element, variant, rim_m, far_m in keys:
        cells, tets = [], None
        for nu in nus:
            r = next((r for r in runs if (r["element"], r["variant"], r["near_cell_m"],
                                          r["far_cell_m"], r["poisson_ratio"])
                      == (element, variant, rim_m, far_m, nu)), None)
            if r is None:
                cells.append("–")
                continue
            tets = r["tets"]
            cells.append(f"{r['frame_ms']:.1f} ms, {100 * r['relative_error']:+.1f} % / "
                         f"{100 * r['layer_relative_error']:+.1f} %")
        kind = f"{element.upper()}{', quarter-point' if variant == 'quarter' else ''}"
        md.append(f"| {kind}, {1e3 * rim_m:g} / {1e3 * far_m:g} | {tets} | "
                  + " | ".join(cells) + " |")
    return md


def chart(bench, runs, file="punch_rim.png",
          title="punch on meshes graded to the rim (Gmsh), nodes only",
          caption="Boussinesq F = 2 a E* d on unstructured meshes graded towards the punch's "
                  "rim (edge on the rim / far from it, mm; P2q diamonds: the quadratic meshes "
                  "with quarter-point nodes at the rim)"):
    # A panel per ν: at 0.49 the linear element's locking sets the scale, and on one panel the
    # quadratic points of both ratios crowd each other's labels.
    nus = sorted({r["poisson_ratio"] for r in runs})
    fig, axes = plt.subplots(1, len(nus), figsize=(6.5 * len(nus), 5.2), squeeze=False)
    note = ("P2q: quarter-point nodes at the rim; "
            if any(r["variant"] == "quarter" for r in runs) else "")
    for axis, nu in zip(axes[0], nus):
        shown = [r for r in runs if r["poisson_ratio"] == nu]
        labels = indentation.pareto_panel(
            axis, shown, sorted({r["variant"] for r in shown}),
            f"{title}, ν {nu:g}\n(labels: edge near / far, mm; {note}lines: Pareto fronts)",
            label=label_of)
        label_log_x(axis)
        place_labels(axis, labels)
    save_figure(fig, bench.path(file))
    return {"file": file,
            "caption": caption + ": the fitted coefficient's error against the bonded layer over "
                       "the median visual frame, linear and quadratic tets at ν 0.45 and 0.49."}


def polygon_stiffness(n):
    """The stiffness of a flat punch whose footprint is the regular n-gon inscribed in its circle,
    over the circle's: the root of their areas' ratio (the module's docstring)."""
    return math.sqrt(n / (2.0 * math.pi) * math.sin(2.0 * math.pi / n))


def polygon_markdown(runs):
    """Per rim edge, its meshes' polygon: nodes, the area it inscribes less than the circle, and
    the stiffness that costs."""
    polygons = sorted({(r["near_cell_m"], r["rim_nodes"]) for r in runs}, reverse=True)
    parts = [f"{1e3 * rim_m:g} mm, {n} nodes: area {100 * (polygon_stiffness(n) ** 2 - 1):+.2f} %, "
             f"stiffness {100 * (polygon_stiffness(n) - 1):+.2f} %" for rim_m, n in polygons]
    return ["The rim polygons (edge on the rim: nodes on it, the area they inscribe against the "
            "circle's, and the stiffness that alone takes off): " + "; ".join(parts) + ".", ""]


def converged_markdown(fine):
    """What the fine mesh, with its edge nodes at the midpoints and at quarter points (`fine`, in
    that order), says of how far the block is from the bonded-layer formula. A conforming mesh
    whose stiffness is integrated exactly is stiffer than the block it discretises, once its rim
    polygon's softening is added back ((1 + error) / polygon_stiffness − 1); the quarter-point
    elements are not integrated exactly at the rim (fem/quarter_point_nodes.h), so theirs bounds
    nothing."""
    said = [f"{label_of(r)} ({r['tets']} tets, {r['frame_ms']:.0f} ms a frame) is "
            f"{100 * r['layer_relative_error']:+.1f} % from the bonded layer at ν "
            f"{indentation.NU:g} ({100 * r['relative_error']:+.1f} % from the half-space)"
            for r in fine]
    circle = [(1.0 + r["layer_relative_error"]) / polygon_stiffness(r["rim_nodes"]) - 1.0
              for r in fine]
    return [f"The reference, tested by a fine mesh: {said[0]}; with quarter-point nodes at the rim "
            f"{said[1]}. A conforming mesh integrated exactly is stiffer than the block, so with "
            f"its rim polygon's {100 * (1 - polygon_stiffness(fine[0]['rim_nodes'])):.2f} % added "
            f"back the plain one says the block is at most about {100 * circle[0]:.1f} % stiffer "
            "than the layer formula. The quarter-point elements are not integrated exactly at the rim, so "
            f"theirs ({100 * circle[1]:+.1f} % with the polygon's share) bounds nothing, but "
            "suggests the block is nearer still: the errors above are the meshes', to about "
            "that.", ""]


def markdown(runs, nus, fine):
    """The experiment's RESULTS.md text from its runs, at the ν charted, and the fine mesh's two
    runs (none in a quick sweep)."""
    md = [f"The punch of the indentation experiment on Gmsh meshes graded towards its rim (edge "
          f"growing linearly from the rim's to the far one over {1e3 * GRADING_DISTANCE_M:g} mm; "
          "nodes only; the quadratic meshes also with the node of each edge leaving the rim "
          f"{QUARTER_POINT_FRACTION:g} of the way along it, quarter-point; errors against the "
          "half-space and the bonded layer):", ""]
    md += table_markdown(runs, nus) + [""] + polygon_markdown(runs + fine)
    md += ["Quadratic against linear at the same frame cost (errors against the bonded layer; "
           "P2q: quarter-point nodes at the rim, against the same linear runs as P2):", ""]
    md += indentation.comparison_markdown(runs, label=label_of) + [""]
    return md + (converged_markdown(fine) if fine else [])


def run(bench):
    meshes = QUICK_MESHES if bench.quick else MESHES
    nus = (indentation.NU,) if bench.quick else indentation.TISSUE_NUS
    runs = []
    for nu in nus:
        runs += [press(bench, element, rim_m, far_m, nu) for element, sizes in meshes.items()
                 for rim_m, far_m in sizes]
        runs += [press(bench, "p2", rim_m, far_m, nu, quarter=True)
                 for rim_m, far_m in meshes["p2"]]
    element, rim_m, far_m = CONVERGED
    fine = ([] if bench.quick else
            [press(bench, element, rim_m, far_m, indentation.NU, quarter=quarter)
             for quarter in (False, True)])
    output = {"runs": runs, "grading_distance_m": GRADING_DISTANCE_M,
              "quarter_point_fraction": QUARTER_POINT_FRACTION,
              "figures": [chart(bench, runs)], "markdown": markdown(runs, nus, fine)}
    if fine:
        output["converged_runs"] = fine
    return output
