"""Indentation of a thick block against closed forms, over mesh resolution (issue 12, item 2).

Hertz: a rigid sphere of radius R pressed d into an elastic half-space, frictionless:
    F = (4/3) E* R^(1/2) d^(3/2),   E* = E / (1 − ν²)          (Johnson, Contact Mechanics, §4.2)
Boussinesq: a rigid flat circular punch of radius a:
    F = K d,   K = 2 a E*                                        (Johnson, §3.7)
Each run is `hapsim sim` of scenes/hertz_indentation.yaml or scenes/flat_punch.yaml (a slow
quasi-static press, no gravity), the lattice `cells` varied. Per visual frame the tool's depth
below the undeformed top and the frame's contact force give a force–depth curve; the law's one
coefficient is fitted by least squares over the depth window, and its relative error is the
experiment's error. A conforming displacement FEM is stiffer than the continuum, and a finite
block bonded at its base stiffer than a half-space: the error should be positive and fall with
the cell size. Linear tetrahedra are also too stiff in volume change as ν nears 1/2 (volumetric
locking); the full run measures how much of the error that is by pressing the middle mesh again
at ν = 0.3 (the closed form's E* follows ν).

Issue 27 adds the quadratic element (`body.element: p2`) on coarser lattices beside the linear
one, each at ν 0.45 and 0.49, and a second reference for Hertz: the block is not a half-space but a
layer of thickness h bonded at its base, which is stiffer. For a sphere on a bonded layer,
Dimitriadis et al. (Biophys. J. 82, 2002, eq. 12) give
    F = F_Hertz · (1 − (2α₀/π) χ + (4α₀²/π²) χ² − (8/π³)(α₀³ + (4π²/15) β₀) χ³
                     + (16 α₀/π⁴)(α₀³ + (3π²/5) β₀) χ⁴),   χ = (R d)^(1/2) / h,
    α₀ = −(1.2876 − 1.4678 ν + 1.3442 ν²)/(1 − ν),  β₀ = (0.6387 − 1.0277 ν + 1.5164 ν²)/(1 − ν),
fitted with the same power law over the same depths. At this block's 0.8 mm it is +11 % at ν 0.45.
For the punch the same kernel gives a closed form to the order of α₀ (derived here, not in the
paper): the layer's surface compliance adds a uniform displacement α₀ F / (π E* h) to the
half-space's under any load, so a punch, whose pressure keeps its shape under a uniform shift,
is exactly that much more compliant:
    K = 2 a E* / (1 + (2α₀/π) χ),   χ = a / h;
its expansion 1 − (2α₀/π) χ + (4α₀²/π²) χ² − … has the form of the α₀ terms of the sphere's series
(a form, not a cross-check: the sphere's contact radius moves with the shift too). The β₀ term
(a kernel quadratic in r) is of order χ³: to first order it pairs the punch's pressure with itself,
⟨r²⟩ = 2/3 a² twice, against 2/3 + 2/5 for the sphere, so it is the sphere's term times 5/4,
−(8/3π) β₀ χ³, under 0.1 % here. The punch's layer adds +11.6 % at ν 0.45 (a/h 0.1).
The full run checks the sphere's correction against the model itself: P2 m4 pressed again into a
block twice as deep and wide, on m 7 whose cell at the focus is the same (2.60 against 2.59 mm),
where the layer formula predicts less stiffening. The punch's is checked from one side by
punch_rim.py's fine mesh.

The punch is pressed three ways (a run's `variant`):
- "features", the scene as it is: the punch's sharp rim presses each face it crosses at the rim
  point and holds the whole face at the punch's depth, so the contact's radius grows by up to one
  surface cell: the error is positive, of the rim's cell size over a;
- "nodes": the tool's features off (`contact.tool_features: false`), only the body's nodes touch
  the punch, the FE convention for a rigid indenter (node-to-surface): the contact ends at the
  outermost node under the punch, and the error goes with where the lattice's nodes fall against
  the rim, either sign;
- "rim": nodes only on the lattice bent into an O-grid with a ring of nodes on the rim
  (`graded.circle_radius_m`, fem/lattice_mesher.h), 0.1 % inside it (3 µm): a node exactly on a
  sharp rim sits on the cylinder's edge, where a round-off's penetration is nearest the side face,
  whose normal is horizontal, and the node holds no load. No face passes under the rim, so the
  contact's edge is the punch's and the error is the element's (and the rim polygon's: a ring of
  8k nodes inscribes 1 − sin(2π/8k)·8k/2π less area than the circle).
A lattice cannot be fine across the rim without being fine along it at the corners: punch_rim.py
presses the punch on unstructured meshes graded towards the rim instead.
"""
import math

from common import draw_pareto, place_labels, plt, save_figure
from common import pareto_front as common_pareto_front

# name, scene, block top z, tool offset (sphere centre or punch centre above its contact point),
# depth window for the fit (m), the law's exponent p (F = C d^p) and its C from the scene's values
E_PA, NU, SPHERE_R_M, PUNCH_A_M = 50000.0, 0.45, 0.01, 0.003
E_STAR = E_PA / (1.0 - NU * NU)
# The full run's second Poisson's ratio, on the middle mesh (cells per axis, grading ratio).
LOW_NU, NU_MESH = 0.3, ((20, 20, 10), 10.0)
# Both elements are pressed at these ν (issue 27: tissue is nearly incompressible).
TISSUE_NUS = (0.45, 0.49)
BLOCK_DEPTH_M = 0.03
CASES = {
    "hertz": {"scene": "scenes/hertz_indentation.yaml", "top_m": 0.03, "offset_m": SPHERE_R_M,
              "window_m": (0.2e-3, 0.8e-3), "power": 1.5,
              "coefficient": 4.0 / 3.0 * E_STAR * math.sqrt(SPHERE_R_M),
              "coefficient_over_E_star": 4.0 / 3.0 * math.sqrt(SPHERE_R_M),
              "law": "Hertz F = (4/3) E* R^1/2 d^3/2"},
    "punch": {"scene": "scenes/flat_punch.yaml", "top_m": 0.03, "offset_m": 0.005,
              "window_m": (0.05e-3, 0.3e-3), "power": 1.0, "coefficient": 2.0 * PUNCH_A_M * E_STAR,
              "coefficient_over_E_star": 2.0 * PUNCH_A_M,
              "law": "Boussinesq F = 2 a E* d"},
}


def lattice(m):
    """The 2m × 2m × m lattice of the sweeps: cells per axis."""
    return (2 * m, 2 * m, m)


# How the punch meets the body: the scene as it is, nodes only, nodes only on a rim-following
# lattice (the module's docstring).
VARIANTS = ("features", "nodes", "rim")
RIM_INSIDE = 1e-3  # the rim's ring of nodes this fraction of a inside the rim (the docstring)
# The rim-following lattices (P1 graded 10:1, P2 20:1, as the sweep's best), whose rings nearest
# a = 3 mm are moved onto the rim from 2.59, 3.32, 2.59 and 3.10 mm (P1 m 8, 10, 12, 14: 16, 24,
# 24 and 32 nodes on the rim) and from 2.71, 1.76, 3.65, 3.65 and 2.71 mm (P2 m 3, m 4,
# 10 × 10 × 4, m 5, m 6: 8, 8, 16, 16 and 16, each with as many edge nodes on the chords).
RIM_P1 = (8, 10, 12, 14)
RIM_P2 = ((lattice(3), 20.0), (lattice(4), 20.0), ((10, 10, 4), 20.0), (lattice(5), 20.0),
          (lattice(6), 20.0))


# Lattices with fewer cells in z than the 2m × 2m × m family, each element's (cells graded as its
# best): the field under a contact is finer across than deep. They fill the fronts between the
# family's meshes (hand runs, Hertz ν 0.45, 2026-11-29: P1 16 × 16 × 6 +24.9 % at 2.1 ms, near m 8's
# +22.1 % at 3.0 ms; P2 8 × 8 × 3 +8.1 % at 2.6 ms, between m 3's +20.9 % at 1.1 ms and m 4's
# +4.9 % at 3.8 ms).
THIN_P1 = ((16, 16, 6), (20, 20, 8))
THIN_P2 = (8, 8, 3)


def meshes(quick, name="hertz"):
    """(element, cells per axis, grading ratio, variant) per run: mostly the 2m × 2m × m lattices
    graded 10 times; quadratic tets also graded 20 times, where their larger cells resolve the
    contact zone better (P2 on 2m × 2m × m at ratio 20 against 10: m 4 +5.0 % against +9.1 % from
    the bonded layer at ν 0.45, hand runs of 2026-11-28), and on 10 × 10 × 4, between m 4 and m 5;
    and the lattices thinner in z (THIN_P1, THIN_P2). The punch again with nodes only, and on rim-following lattices, where frames are near 10 ms
    and below."""
    if quick:
        runs = [("p1", lattice(6), 10.0, "features"), ("p1", lattice(8), 10.0, "features"),
                ("p2", lattice(3), 10.0, "features")]
        return runs + ([("p2", lattice(4), 20.0, "rim")] if name == "punch" else [])
    runs = ([("p1", lattice(m), 10.0, "features") for m in (6, 8, 10, 12, 14, 16)]
            + [("p1", lattice(10), 5.0, "features"), ("p1", lattice(10), 20.0, "features")]
            + [("p2", lattice(m), 10.0, "features") for m in (3, 4, 5, 6)]
            + [("p2", lattice(m), 20.0, "features") for m in (3, 4, 5)]
            + [("p2", (10, 10, 4), 20.0, "features")]
            + [("p1", cells, 10.0, "features") for cells in THIN_P1]
            + [("p2", THIN_P2, 20.0, "features")])
    if name == "punch":
        runs += ([("p1", lattice(m), 10.0, "nodes") for m in (6, 8, 10, 12)]
                 + [("p2", lattice(m), 20.0, "nodes") for m in (3, 4, 5)]
                 + [("p2", (10, 10, 4), 20.0, "nodes")]
                 + [("p1", lattice(m), 10.0, "rim") for m in RIM_P1]
                 + [("p2", cells, ratio, "rim") for cells, ratio in RIM_P2])
    return runs


def layer_factor(depth_m, nu, thickness_m=BLOCK_DEPTH_M, name="hertz"):
    """A bonded layer's force over the half-space's: Dimitriadis et al. 2002 for the sphere (R),
    its α₀ term for the flat punch (a; the module's docstring)."""
    a0 = -(1.2876 - 1.4678 * nu + 1.3442 * nu * nu) / (1.0 - nu)
    b0 = (0.6387 - 1.0277 * nu + 1.5164 * nu * nu) / (1.0 - nu)
    pi = math.pi
    if name == "punch":
        return 1.0 / (1.0 + 2.0 * a0 / pi * PUNCH_A_M / thickness_m)
    chi = math.sqrt(SPHERE_R_M * depth_m) / thickness_m
    return (1.0 - 2.0 * a0 / pi * chi + 4.0 * a0 * a0 / pi ** 2 * chi ** 2
            - 8.0 / pi ** 3 * (a0 ** 3 + 4.0 * pi ** 2 / 15.0 * b0) * chi ** 3
            + 16.0 * a0 / pi ** 4 * (a0 ** 3 + 3.0 * pi ** 2 / 5.0 * b0) * chi ** 4)


def layer_coefficient(curve, name, case, nu, thickness_m=BLOCK_DEPTH_M):
    """The bonded layer's force fitted as `fit` fits the run's: same law, same depths."""
    num = den = 0.0
    low, high = case["window_m"]
    half_space = case["coefficient_over_E_star"] * E_PA / (1.0 - nu * nu)
    for depth_m, _ in curve:
        if low <= depth_m <= high:
            basis = depth_m ** case["power"]
            num += half_space * basis * layer_factor(depth_m, nu, thickness_m, name) * basis
            den += basis * basis
    return num / den


def fit(frames, case):
    """Least-squares C of F = C d^p over the depth window; the curve (d, F) of every frame."""
    curve, num, den = [], 0.0, 0.0
    low, high = case["window_m"]
    for row in frames:
        depth_m = case["top_m"] + case["offset_m"] - row["tool_z_m"]
        force_N = row["contact_force_z_N"]
        curve.append((depth_m, force_N))
        if low <= depth_m <= high:
            basis = depth_m ** case["power"]
            num += force_N * basis
            den += basis * basis
    if den == 0.0:
        raise RuntimeError(f"{case['scene']}: no frame reached the depth window {case['window_m']}")
    return num / den, curve


def mesh_name(cells):
    """m6 for the 2m × 2m × m lattice of m 6, else 10x10x4."""
    return f"m{cells[2]}" if tuple(cells) == lattice(cells[2]) else "x".join(map(str, cells))


def press(bench, name, case, cells, ratio, nu=NU, element="p1", depth_scale=1,
          variant="features"):
    """One indentation run on a lattice of `cells` per axis graded towards the top centre; its
    fit. depth_scale 2: the block twice as deep and wide (the same cells), its top where it was;
    variant: one of VARIANTS."""
    label = (f"{name}_{element}_{mesh_name(cells)}_r{ratio:g}_nu{nu:g}"
             + ("" if depth_scale == 1 else f"_deep{depth_scale}")
             + ("" if variant == "features" else f"_{variant}"))
    tets = 5 * cells[0] * cells[1] * cells[2]  # five tets per cell (fem/lattice_mesher.h)
    bench.progress(f"indentation: {label} ({tets} tets)")
    half_width_m, depth_m = 0.03 * depth_scale, BLOCK_DEPTH_M * depth_scale
    edits = {"body.mesh.box.cells": list(cells),
             "body.mesh.box.graded": {"focus_m": [0.0, 0.0, 0.03], "ratio": ratio},
             "body.material.poisson_ratio": nu, "body.element": element}
    if variant not in VARIANTS:
        raise ValueError(f"unknown variant {variant}")
    if variant in ("nodes", "rim"):
        edits["contact.tool_features"] = False
    if variant == "rim":
        edits["body.mesh.box.graded"]["circle_radius_m"] = PUNCH_A_M * (1.0 - RIM_INSIDE)
    if depth_scale != 1:
        edits["body.mesh.box.min_m"] = [-half_width_m, -half_width_m, 0.03 - depth_m]
        edits["body.mesh.box.max_m"] = [half_width_m, half_width_m, 0.03]
        edits["body.fixed"] = {"min_m": [-2 * half_width_m, -2 * half_width_m, 0.03 - depth_m - 1e-4],
                               "max_m": [2 * half_width_m, 2 * half_width_m, 0.03 - depth_m + 1e-4]}
    summary, frames, _ = bench.sim(bench.scene_variant(case["scene"], edits, label), label)
    return {"element": element, "cells": list(cells), "ratio": ratio, "variant": variant,
            "tets": tets, "poisson_ratio": nu, "block_depth_m": depth_m,
            **score(summary, frames, name, case, nu, depth_m)}


def score(summary, frames, name, case, nu, depth_m=BLOCK_DEPTH_M):
    """A press's figures: its frame cost, the fitted coefficient and its error against the
    half-space and against the bonded layer of depth_m, and the force–depth curve."""
    coefficient, curve = fit(frames, case)
    analytic = case["coefficient_over_E_star"] * E_PA / (1.0 - nu * nu)
    layer = layer_coefficient(curve, name, case, nu, depth_m)
    return {"frame_ms": summary["frame_stage_median_ms"]["total"],
            "max_contacts": summary["max_contacts"], "fitted_coefficient": coefficient,
            "analytic_coefficient": analytic, "relative_error": coefficient / analytic - 1.0,
            "layer_coefficient": layer, "layer_relative_error": coefficient / layer - 1.0,
            "curve": curve}


def run_case(bench, name, case):
    nus = (NU,) if bench.quick else TISSUE_NUS
    return [press(bench, name, case, cells, ratio, nu, element, variant=variant)
            for nu in nus for element, cells, ratio, variant in meshes(bench.quick, name)]


def locking_markdown(name, at_nu, at_low_nu):
    """What pressing the same mesh at a lower ν says about the error (measured, not assumed)."""
    e_nu, e_low = 100 * at_nu["relative_error"], 100 * at_low_nu["relative_error"]
    said = (f"On {mesh_label(at_nu['cells'])}, ratio {at_nu['ratio']:g} the error is {e_nu:+.1f} % at ν "
            f"{NU} and {e_low:+.1f} % at ν {LOW_NU} (each against its own E*). ")
    if e_low < 0.5 * e_nu:
        said += ("Over half of the excess stiffness goes with ν: the volumetric locking of linear "
                 "tetrahedra near incompressibility, which refinement removes only slowly; the "
                 "rest is the discretisation of the contact zone and the finite block.")
    elif e_low < 0.9 * e_nu:
        said += ("Part of the excess stiffness goes with ν (the volumetric locking of linear "
                 "tetrahedra near incompressibility); most is the discretisation of the contact "
                 "zone and the finite, bonded block.")
    else:
        said += ("ν does not explain the excess stiffness: it is the discretisation of the "
                 "contact zone and the finite, bonded block.")
    return said


# (element, ν): colour, marker of a Pareto series; the variants "nodes" and "rim" share a panel
# (the punch's right-hand one), the nodes-only runs drawn as triangles, and the quarter-point
# quadratic runs (punch_rim.py) as diamonds beside their plain meshes' squares.
SERIES = {("p1", 0.45): ("k", "o"), ("p1", 0.49): ("0.55", "o"),
          ("p2", 0.45): ("tab:blue", "s"), ("p2", 0.49): ("tab:cyan", "s")}
VARIANT_TEXT = {"features": "", "nodes": ", nodes only", "rim": ", nodes only, rim-following",
                "graded": ", nodes only, graded to the rim (Gmsh)",
                "disk": ", graded from the contact zone (Gmsh)",
                "quarter": ", nodes only, graded to the rim (Gmsh), quarter-point"}
VARIANT_MARKER = {"nodes": "^", "quarter": "D"}
# The linear runs a quadratic variant is compared with: its own, but for the quarter-point meshes,
# whose nodes the linear element does not have (the same meshes' kind, graded to the rim).
P1_VARIANT_OF = {"quarter": "graded"}


def mesh_label(cells):
    """"m 6" for the 2m × 2m × m lattice of m 6, else "10 × 10 × 4"."""
    return (f"m {cells[2]}" if tuple(cells) == lattice(cells[2])
            else " × ".join(map(str, cells)))


def label_of(r):
    return (f"{r['element'].upper()} {mesh_name(r['cells'])}"
            + ("" if r["ratio"] == 10.0 else f" r{r['ratio']:g}")
            + ("" if r["variant"] == "features" else f" {r['variant']}"))


def pareto_panel(axis, results, variants, title, label=None):
    """Per element, ν and variant, the runs' error against the bonded layer over the frame cost
    and their front; the labels to place. label(run): a point's name (label_of)."""
    label = label or label_of
    labels = []
    for variant in variants:
        for (element, nu), (color, marker) in SERIES.items():
            series = [r for r in results
                      if (r["element"], r["poisson_ratio"], r["variant"]) == (element, nu, variant)]
            if series:
                labels += draw_pareto(
                    axis, [(r["frame_ms"], 100 * r["layer_relative_error"]) for r in series],
                    [label(r) for r in series], color=color,
                    marker=VARIANT_MARKER.get(variant, marker),
                    name=f"{element.upper()}, ν {nu:g}{VARIANT_TEXT[variant]}")
    axis.axhline(0.0, color="k", lw=0.8)
    axis.set(xscale="log", xlabel="median visual frame (ms)",
             ylabel="error against the bonded layer (%)", title=title)
    axis.title.set_fontsize(10)
    axis.legend(fontsize=6)
    axis.grid(True, alpha=0.3)
    return labels


def chart(bench, name, case, results):
    node_variants = [v for v in ("nodes", "rim") if any(r["variant"] == v for r in results)]
    fig, axes = plt.subplots(1, 3 if node_variants else 2,
                             figsize=(18 if node_variants else 12, 4.8))
    left = axes[0]
    # Linear tets graded 10:1 (their best grading), quadratic 20:1 (theirs) and 10:1 where the
    # quick sweep has no 20:1 mesh.
    best_ratio = {"p1": 10.0, "p2": 20.0 if any(r["element"] == "p2" and r["ratio"] == 20.0
                                                  and r["variant"] == "features" for r in results)
                  else 10.0}
    shown = [r for r in results if r["poisson_ratio"] == NU and r["variant"] == "features"
             and r["ratio"] == best_ratio[r["element"]]]
    top_d = max(d for r in shown for d, _ in r["curve"])
    ds = [top_d * i / 100 for i in range(101)]
    left.plot([1e3 * d for d in ds], [case["coefficient"] * d ** case["power"] for d in ds], "k-",
              lw=2, label=case["law"] + " (half-space)")
    left.plot([1e3 * d for d in ds],
              [case["coefficient"] * d ** case["power"] * layer_factor(d, NU, name=name) for d in ds],
              "k:", lw=2, label="bonded 30 mm layer (Dimitriadis et al. 2002"
              + ("" if name == "hertz" else "; its α₀ term for a punch, derived here") + ")")
    for r in shown:
        left.plot([1e3 * d for d, _ in r["curve"] if d > 0], [f for d, f in r["curve"] if d > 0],
                  "-" if r["element"] == "p1" else "--", lw=1,
                  label=f"{label_of(r)} ({r['tets']} tets)")
    left.axvspan(1e3 * case["window_m"][0], 1e3 * case["window_m"][1], color="0.9", zorder=0)
    left.set(xlabel="depth below the undeformed top (mm)", ylabel="contact force (N)",
             title=f"{name}, ν {NU}: force against depth (grey: fit window)")
    left.title.set_fontsize(10)
    left.legend(fontsize=6)
    left.grid(True, alpha=0.3)
    labels = {axes[1]: pareto_panel(
        axes[1], results, ["features"],
        f"{name}: error against cost" + (", the scene's contact" if node_variants else "")
        + "\n(lines: Pareto fronts)")}
    if node_variants:
        said = " and ".join({"nodes": "nodes only (triangles)",
                             "rim": "nodes only on lattices following the rim"}[v]
                            for v in node_variants)
        labels[axes[2]] = pareto_panel(axes[2], results, node_variants,
                                       f"{name}: {said}\n(lines: Pareto fronts)")
    for axis, its_labels in labels.items():  # once every panel is set up (common.place_labels)
        place_labels(axis, its_labels)
    save_figure(fig, bench.path(f"{name}.png"))
    return {"file": f"{name}.png",
            "caption": f"{case['law']}: force against depth per mesh (ν {NU}; linear tets graded "
                       f"10:1 solid, quadratic {best_ratio['p2']:g}:1 dashed; the half-space and the bonded 30 mm "
                       "layer in black), and the fitted coefficient's error against the bonded "
                       "layer over the median visual frame for both elements at ν 0.45 and 0.49"
                       + ("" if not node_variants else
                          "; the scene's contact (its rim's features press the faces under it), "
                          "and only the body's nodes touching the punch, on the lattices and on "
                          "lattices with a ring of nodes on the rim") + "."}


def pareto_front(runs, key):
    """(frame_ms, error) of the runs on the front of |error| against cost (common.pareto_front),
    cheapest first: each cheaper than the next and more wrong."""
    front = common_pareto_front([(r["frame_ms"], abs(r[key])) for r in runs])
    return [(runs[i]["frame_ms"], runs[i][key]) for i in front]


def error_at_cost(front_runs, frame_ms, key):
    """P1's error at a frame cost, interpolated (log cost, linear error) along its Pareto front;
    None outside the front's range of costs."""
    front = pareto_front(front_runs, key)
    for (c0, e0), (c1, e1) in zip(front, front[1:]):
        if c0 <= frame_ms <= c1:
            t = math.log(frame_ms / c0) / math.log(c1 / c0)
            return e0 + t * (e1 - e0)
    return None


def cost_at_error(front_runs, error, key):
    """(frame_ms, extrapolated): the frame cost at which P1's front is |error| off. Between two
    front runs |error| is interpolated in log cost, so where their errors have one sign this is
    the inverse of error_at_cost. Below the cheapest run it follows the power law |error| ∝ cost^s
    through the two cheapest front runs (extrapolated True), the form a mesh's convergence takes
    (error ∝ h^p, cost ∝ h^−q). None if the front has fewer than two runs, or is more wrong than
    |error| even at its dearest run."""
    front = [(c, abs(e)) for c, e in pareto_front(front_runs, key)]
    target = abs(error)
    if len(front) < 2 or target < front[-1][1]:
        return None
    for (c0, e0), (c1, e1) in zip(front, front[1:]):
        if e1 <= target <= e0:  # e1 < e0: the front's |error| falls strictly
            return math.exp(math.log(c0) + (target - e0) / (e1 - e0) * math.log(c1 / c0)), False
    (c0, e0), (c1, e1) = front[0], front[1]
    if e1 <= 0.0:
        return None
    slope = math.log(e1 / e0) / math.log(c1 / c0)  # negative: e1 < e0, c1 > c0
    return c0 * (target / e0) ** (1.0 / slope), True


def third_clause(p1_runs, run, key):
    """Where P2's error is above a third of P1's at its cost: how much shorter its frame would
    have to be, on the same mesh, for P1's error there to be three times its own (the issue's
    target, issue 27), from where P1's front is 3 |error| off (cost_at_error)."""
    reach = cost_at_error(p1_runs, 3.0 * run[key], key)
    if reach is None:
        return ""
    frame_ms, extrapolated = reach
    how = (" (a power law through its two cheapest front meshes, extrapolated)" if extrapolated
           else "")
    off = f"{100 * 3 * abs(run[key]):.0f} %"
    if not frame_ms > run["frame_ms"] / 1000.0:  # also an underflow to zero
        return (f". A third of P1's error would take this mesh's frame over 1000× shorter: P1 is "
                f"{off} off only below {run['frame_ms'] / 1000.0:.2g} ms{how}")
    return (f". A third of P1's error would take this mesh's frame "
            f"{run['frame_ms'] / frame_ms:.1f}× shorter: P1 is {off} off at {frame_ms:.2g} ms{how}")


def comparison_markdown(results, label=None):
    """Per quadratic run: the linear element's error at the same frame cost (the same contact, its
    `variant`, or P1_VARIANT_OF's), and the ratio; errors against the bonded layer. label(run): its
    name (label_of)."""
    label = label or label_of
    lines = []
    key = "layer_relative_error"
    for nu in sorted({r["poisson_ratio"] for r in results}):
        for r in (r for r in results if r["element"] == "p2" and r["poisson_ratio"] == nu):
            p1_variant = P1_VARIANT_OF.get(r["variant"], r["variant"])
            p1 = [q for q in results if (q["element"], q["poisson_ratio"], q["variant"])
                  == ("p1", nu, p1_variant)]
            p1_error = error_at_cost(p1, r["frame_ms"], key)
            if p1_error is None or abs(p1_error) < 1e-3:
                lines.append(f"- ν {nu:g}, {label(r)} ({r['frame_ms']:.1f} ms): "
                             f"{100 * r[key]:+.1f} %; no P1 error to compare at that cost "
                             "(none charted there, or P1 crosses zero)")
            else:
                ratio = abs(r[key] / p1_error)
                lines.append(f"- ν {nu:g}, {label(r)} ({r['frame_ms']:.1f} ms): "
                             f"{100 * r[key]:+.1f} % against P1's {100 * p1_error:+.1f} % at the "
                             f"same cost (ratio {ratio:.2f})"
                             + (third_clause(p1, r, key) if ratio > 1 / 3 else ""))
    return lines


def table_markdown(results):
    head = "error (half-space / bonded layer)"
    md = [f"| element, lattice (m: 2m × 2m × m cells), grading | tets | ν 0.45: frame, {head} | "
          f"ν 0.49: frame, {head} |", "|---|---:|---:|---:|"]
    keys = []
    for r in results:
        key = (r["element"], tuple(r["cells"]), r["ratio"], r["variant"])
        if key not in keys:
            keys.append(key)
    for element, cells, ratio, variant in keys:
        cells_md = []
        for nu in TISSUE_NUS:
            r = next((r for r in results if (r["element"], tuple(r["cells"]), r["ratio"],
                                             r["variant"], r["poisson_ratio"])
                      == (element, cells, ratio, variant, nu)), None)
            if r is None:
                cells_md.append("–")
                continue
            cells_md.append(f"{r['frame_ms']:.1f} ms, {100 * r['relative_error']:+.1f} % / "
                            f"{100 * r['layer_relative_error']:+.1f} %")
        tets = 5 * cells[0] * cells[1] * cells[2]
        md.append(f"| {element.upper()}, {mesh_label(cells)}, ratio {ratio:g}"
                  f"{VARIANT_TEXT[variant]} | {tets} | {cells_md[0]} | {cells_md[1]} |")
    return md


def focus_cell_m(run):
    """The width of the lattice's cell at the focus along x: fem/lattice_mesher.cc's graded axis
    (cells uniform in ψ(x) = ln(1 + s|x − f|)/s, s = (ratio − 1)/half-width), focus at the centre."""
    half_m = run["block_depth_m"]  # both blocks are twice as wide as they are deep
    slope = (run["ratio"] - 1.0) / half_m
    d_psi = 2.0 * math.log1p(slope * half_m) / slope / run["cells"][0]
    if run["cells"][0] % 2 == 0:  # a node at the focus: the first cell is [0, ψ⁻¹(Δψ)]
        return math.expm1(slope * d_psi) / slope
    return 2.0 * math.expm1(slope * 0.5 * d_psi) / slope


def depth_check_markdown(standard, deep):
    """The layer correction tested by the model: the same contact-zone cells, a deeper block."""
    def stiffening(r):  # the layer's coefficient over the half-space's
        return r["layer_coefficient"] / r["analytic_coefficient"]

    def errors(r):
        return (f"{100 * r['relative_error']:+.1f} % against the half-space, "
                f"{100 * r['layer_relative_error']:+.1f} % against the bonded layer")
    return (f"The layer correction, checked on the model: {label_of(standard)} in the 30 mm block "
            f"gives {errors(standard)}; {mesh_label(deep['cells'])} in a block 60 mm deep and "
            f"120 mm wide, whose cell at the focus is {1e3 * focus_cell_m(deep):.2f} mm wide "
            f"against {1e3 * focus_cell_m(standard):.2f} mm, gives {errors(deep)}. The half-space's excess falls by "
            f"{100 * (standard['relative_error'] - deep['relative_error']):.1f} points; the formula "
            f"predicts {100 * (stiffening(standard) - stiffening(deep)):.1f}.")


def run(bench):
    output = {"figures": [], "markdown": []}
    md = output["markdown"]
    for name, case in CASES.items():
        results = run_case(bench, name, case)
        output[name] = {"law": case["law"], "analytic_coefficient": case["coefficient"],
                        "window_m": case["window_m"],
                        "runs": [{k: v for k, v in r.items() if k != "curve"} for r in results]}
        at_nu = next((r for r in results if (r["element"], tuple(r["cells"]), r["ratio"],
                                             r["variant"], r["poisson_ratio"])
                      == ("p1", *NU_MESH, "features", NU)), None)
        at_low_nu = None
        if at_nu is not None:  # the full run's meshes include it
            at_low_nu = press(bench, name, case, *NU_MESH, nu=LOW_NU)
            output[name]["low_poisson_run"] = {k: v for k, v in at_low_nu.items() if k != "curve"}
        output["figures"].append(chart(bench, name, case, results))
        md.append(f"**{name}** ({case['law']}, E {E_PA:g} Pa; fit over depths "
                  f"{1e3 * case['window_m'][0]:g}–{1e3 * case['window_m'][1]:g} mm; median visual "
                  "frame on one core):")
        md.append("")
        md += table_markdown(results)
        md.append("")
        md.append("Quadratic against linear at the same frame cost (errors against the bonded "
                  "layer" + ("; each way of contact against the same way):" if name == "punch"
                             else "):"))
        md.append("")
        md += comparison_markdown(results)
        md.append("")
        if at_low_nu is not None:
            md += [locking_markdown(name, at_nu, at_low_nu), ""]
        if name == "hertz" and not bench.quick:
            standard = next(r for r in results
                            if (r["element"], tuple(r["cells"]), r["ratio"], r["variant"],
                                r["poisson_ratio"]) == ("p2", lattice(4), 10.0, "features", NU))
            deep = press(bench, name, case, lattice(7), 10.0, NU, "p2", depth_scale=2)
            output[name]["deep_block_run"] = {k: v for k, v in deep.items() if k != "curve"}
            md += [depth_check_markdown(standard, deep), ""]
    return output
