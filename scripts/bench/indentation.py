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
"""
import math

from common import draw_pareto, place_labels, plt, save_figure

# name, scene, block top z, tool offset (sphere centre or punch centre above its contact point),
# depth window for the fit (m), the law's exponent p (F = C d^p) and its C from the scene's values
E_PA, NU, SPHERE_R_M, PUNCH_A_M = 50000.0, 0.45, 0.01, 0.003
E_STAR = E_PA / (1.0 - NU * NU)
# The full run's second Poisson's ratio, on the middle mesh (cells, grading ratio).
LOW_NU, NU_MESH = 0.3, (10, 10.0)
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


def meshes(quick):
    """(cells m: lattice 2m x 2m x m, grading ratio) per run."""
    if quick:
        return [(6, 10.0), (8, 10.0)]
    return [(6, 10.0), (8, 10.0), (10, 10.0), (12, 10.0), (14, 10.0), (16, 10.0),
            (10, 5.0), (10, 20.0)]


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


def press(bench, name, case, cells, ratio, nu=NU):
    """One indentation run on a 2m × 2m × m lattice graded towards the top centre; its fit."""
    label = f"{name}_m{cells}_r{ratio:g}" + ("" if nu == NU else f"_nu{nu:g}")
    bench.progress(f"indentation: {label} ({20 * cells ** 3} tets)")
    edits = {"body.mesh.box.cells": [2 * cells, 2 * cells, cells],
             "body.mesh.box.graded": {"focus_m": [0.0, 0.0, 0.03], "ratio": ratio}}
    if nu != NU:
        edits["body.material.poisson_ratio"] = nu
    summary, frames, _ = bench.sim(bench.scene_variant(case["scene"], edits, label), label)
    coefficient, curve = fit(frames, case)
    analytic = case["coefficient_over_E_star"] * E_PA / (1.0 - nu * nu)
    return {"cells": cells, "ratio": ratio, "tets": 20 * cells ** 3, "poisson_ratio": nu,
            "frame_ms": summary["frame_stage_median_ms"]["total"],
            "max_contacts": summary["max_contacts"], "fitted_coefficient": coefficient,
            "analytic_coefficient": analytic, "relative_error": coefficient / analytic - 1.0,
            "curve": curve}


def run_case(bench, name, case):
    return [press(bench, name, case, cells, ratio) for cells, ratio in meshes(bench.quick)]


def locking_markdown(name, at_nu, at_low_nu):
    """What pressing the same mesh at a lower ν says about the error (measured, not assumed)."""
    e_nu, e_low = 100 * at_nu["relative_error"], 100 * at_low_nu["relative_error"]
    said = (f"On m {at_nu['cells']}, ratio {at_nu['ratio']:g} the error is {e_nu:+.1f} % at ν "
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


def chart(bench, name, case, results):
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    top_d = max(d for r in results for d, _ in r["curve"])
    ds = [top_d * i / 100 for i in range(101)]
    left.plot([1e3 * d for d in ds], [case["coefficient"] * d ** case["power"] for d in ds], "k-",
              lw=2, label=case["law"])
    for r in results:
        left.plot([1e3 * d for d, _ in r["curve"] if d > 0], [f for d, f in r["curve"] if d > 0],
                  lw=1, label=f"m {r['cells']}, ratio {r['ratio']:g} ({r['tets']} tets)")
    left.axvspan(1e3 * case["window_m"][0], 1e3 * case["window_m"][1], color="0.9", zorder=0)
    left.set(xlabel="depth below the undeformed top (mm)", ylabel="contact force (N)",
             title=f"{name}: force against depth (grey: fit window)")
    left.legend(fontsize=7)
    labels = draw_pareto(right, [(r["frame_ms"], 100 * r["relative_error"]) for r in results],
                         [f"m{r['cells']} r{r['ratio']:g}" for r in results])
    right.set(xscale="log", xlabel="median visual frame (ms)",
              ylabel="error of the fitted coefficient (%)",
              title=f"{name}: error against cost (line: Pareto front)")
    for axis in (left, right):
        axis.grid(True, alpha=0.3)
    place_labels(right, labels)
    save_figure(fig, bench.path(f"{name}.png"))
    return {"file": f"{name}.png",
            "caption": f"{case['law']}: force against depth per mesh, and the fitted coefficient's "
                       "error against the median visual frame."}


def run(bench):
    output = {"figures": [], "markdown": []}
    md = output["markdown"]
    for name, case in CASES.items():
        results = run_case(bench, name, case)
        output[name] = {"law": case["law"], "analytic_coefficient": case["coefficient"],
                        "window_m": case["window_m"],
                        "runs": [{k: v for k, v in r.items() if k != "curve"} for r in results]}
        at_nu = next((r for r in results if (r["cells"], r["ratio"]) == NU_MESH), None)
        at_low_nu = None
        if at_nu is not None:  # the full run's meshes include it
            at_low_nu = press(bench, name, case, *NU_MESH, nu=LOW_NU)
            output[name]["low_poisson_run"] = {k: v for k, v in at_low_nu.items() if k != "curve"}
        output["figures"].append(chart(bench, name, case, results))
        md.append(f"**{name}** ({case['law']}, E {E_PA:g} Pa, ν {NU}; fit over depths "
                  f"{1e3 * case['window_m'][0]:g}–{1e3 * case['window_m'][1]:g} mm):")
        md.append("")
        md.append("| lattice (2m × 2m × m), grading | tets | median frame (ms) | max contacts | "
                  "error of the coefficient |")
        md.append("|---|---:|---:|---:|---:|")
        for r in results:
            md.append(f"| m {r['cells']}, ratio {r['ratio']:g} | {r['tets']} | {r['frame_ms']:.1f} "
                      f"| {r['max_contacts']} | {100 * r['relative_error']:+.1f} % |")
        md.append("")
        if at_low_nu is not None:
            md += [locking_markdown(name, at_nu, at_low_nu), ""]
    return output
