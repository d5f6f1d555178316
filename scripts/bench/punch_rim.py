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
side: a conforming mesh is stiffer than the block it discretises, so the block is at most that much
stiffer than the layer formula says (its finite width, 20 a, is not in the formula either).
"""
import os

import yaml

import indentation
from common import REPO, BenchError, place_labels, plt, save_figure

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
_MADE = {}  # (bench's folder, case, h_rim, h_far): (mesh file, tets); each mesh made once


def make_mesh(bench, rim_m, far_m, name="punch"):
    """The block's mesh file (OUT/meshes/) and its tet count, from punch_block_mesh, which the
    build puts beside `hapsim` (BUILD/apps/hapsim, BUILD/tests/punch_block_mesh). The block's
    corners are the case's scene's; name "punch" grades from the rim, "hertz" from the disk."""
    prefix, _, grading, _ = GRADED_CASES[name]
    key = (bench.out_dir, name, rim_m, far_m)
    if key in _MADE:
        return _MADE[key]
    program = os.path.join(os.path.dirname(os.path.dirname(bench.hapsim)), "tests",
                           "punch_block_mesh")
    if not os.access(program, os.X_OK):
        raise BenchError(f"{program} is missing: the build makes it with the tests")
    with open(os.path.join(REPO, indentation.CASES[name]["scene"])) as f:
        box = yaml.safe_load(f)["body"]["mesh"]["box"]
    path = bench.path("meshes", f"{prefix}_{1e3 * rim_m:g}mm_{1e3 * far_m:g}mm.msh")
    out = bench.run_program(program, "--min-m", *box["min_m"], "--max-m", *box["max_m"],
                            *grading, "--rim-cell-size-m", rim_m, "--cell-size-m", far_m,
                            "--grading-distance-m", GRADING_DISTANCE_M, "--out", path)
    _MADE[key] = (path, int(out.split()[-1]))
    return _MADE[key]


def press(bench, element, rim_m, far_m, nu, name="punch"):
    """One press on the graded mesh (h_rim, h_far) in `element` at ν: the punch nodes only, the
    sphere as its scene has it; its fit and errors as indentation.press gives them."""
    case = indentation.CASES[name]
    prefix, variant, _, contact_edits = GRADED_CASES[name]
    label = f"{prefix}_{element}_{1e3 * rim_m:g}mm_{1e3 * far_m:g}mm_nu{nu:g}"
    bench.progress(f"{prefix}: {label}")
    mesh_path, tets = make_mesh(bench, rim_m, far_m, name)
    edits = {"body.mesh": {"file": mesh_path}, "body.material.poisson_ratio": nu,
             "body.element": element, **contact_edits}
    summary, frames, _ = bench.sim(bench.scene_variant(case["scene"], edits, label), label)
    figures = indentation.score(summary, frames, name, case, nu)
    figures.pop("curve")
    # near_cell_m: the edge on the rim (punch) or the disk (sphere).
    return {"element": element, "variant": variant, "near_cell_m": rim_m, "far_cell_m": far_m,
            "tets": tets, "poisson_ratio": nu, **figures}


def label_of(r):
    return f"{r['element'].upper()} {1e3 * r['near_cell_m']:g}/{1e3 * r['far_cell_m']:g}"


def table_markdown(runs, nus, where="rim"):
    md = [f"| element, edge on the {where} / far (mm) | tets | "
          + " | ".join(f"ν {nu:g}: frame, error (half-space / bonded layer)" for nu in nus) + " |",
          "|---|---:|" + "---:|" * len(nus)]
    keys = []
    for r in runs:
        key = (r["element"], r["near_cell_m"], r["far_cell_m"])
        if key not in keys:
            keys.append(key)
    for element, rim_m, far_m in keys:
        cells, tets = [], None
        for nu in nus:
            r = next((r for r in runs if (r["element"], r["near_cell_m"], r["far_cell_m"],
                                          r["poisson_ratio"]) == (element, rim_m, far_m, nu)),
                     None)
            if r is None:
                cells.append("–")
                continue
            tets = r["tets"]
            cells.append(f"{r['frame_ms']:.1f} ms, {100 * r['relative_error']:+.1f} % / "
                         f"{100 * r['layer_relative_error']:+.1f} %")
        md.append(f"| {element.upper()}, {1e3 * rim_m:g} / {1e3 * far_m:g} | {tets} | "
                  + " | ".join(cells) + " |")
    return md


def chart(bench, runs, file="punch_rim.png",
          title="punch on meshes graded to the rim (Gmsh), nodes only",
          caption="Boussinesq F = 2 a E* d on unstructured meshes graded towards the punch's "
                  "rim (edge on the rim / far from it, mm)"):
    fig, axis = plt.subplots(figsize=(7, 4.8))
    labels = indentation.pareto_panel(
        axis, runs, sorted({r["variant"] for r in runs}),
        title + "\n(labels: edge near / far, mm; lines: Pareto fronts)", label=label_of)
    place_labels(axis, labels)
    save_figure(fig, bench.path(file))
    return {"file": file,
            "caption": caption + ": the fitted coefficient's error against the bonded layer over "
                       "the median visual frame, linear and quadratic tets at ν 0.45 and 0.49."}


def run(bench):
    meshes = QUICK_MESHES if bench.quick else MESHES
    nus = (indentation.NU,) if bench.quick else indentation.TISSUE_NUS
    runs = [press(bench, element, rim_m, far_m, nu) for nu in nus
            for element, sizes in meshes.items() for rim_m, far_m in sizes]
    output = {"runs": runs, "grading_distance_m": GRADING_DISTANCE_M,
              "figures": [chart(bench, runs)]}
    md = [f"The punch of the indentation experiment on Gmsh meshes graded towards its rim (edge "
          f"growing linearly from the rim's to the far one over {1e3 * GRADING_DISTANCE_M:g} mm; "
          "nodes only; errors against the half-space and the bonded layer):", ""]
    md += table_markdown(runs, nus) + ["", "Quadratic against linear at the same frame cost "
                                       "(errors against the bonded layer):", ""]
    md += indentation.comparison_markdown(runs, label=label_of) + [""]
    if not bench.quick:
        element, rim_m, far_m = CONVERGED
        fine = press(bench, element, rim_m, far_m, indentation.NU)
        output["converged_run"] = fine
        md += [f"The reference, tested by a fine mesh: {label_of(fine)} ({fine['tets']} tets, "
               f"{fine['frame_ms']:.0f} ms a frame) is "
               f"{100 * fine['layer_relative_error']:+.1f} % from the bonded layer at ν "
               f"{indentation.NU:g} ({100 * fine['relative_error']:+.1f} % from the half-space). "
               "A conforming mesh is stiffer than the block, so the block is at most that much "
               "stiffer than the layer formula: the errors above are the meshes', to about that.",
               ""]
    output["markdown"] = md
    return output
