"""Stability map 6: maps 1–5 again on a quadratic body (issue 27: "the stability maps still pass, no
new unstable cell"; see stability.py).

Every cell of maps 1–5 is run again with 10-node tetrahedra (`body.element: p2`) and compared with
the linear body's run on the same cell:
- map 1 on block_tiny's own 8 × 8 × 3 lattice, now quadratic: the explicit limit against its own
  2/ω_max (the HRZ-lumped mass puts little mass on the corners, so ω_max is higher than the linear
  body's and the limit lower), implicit Euler at 100 times it;
- maps 2–5 on block_press quadratic on an 8 × 8 × 2 lattice: 17 × 17 × 5 = 1,445 nodes against the
  linear 15 × 15 × 3 lattice's 1,024, the nearest lattice with about the same unknowns (the same
  cells, quadratic, would have 6.6 times as many). The release map's baseline is the quadratic
  body's own 1 kHz reference.

Criterion, each map's own. A new unstable cell is one where the quadratic body fails and the linear
body, on the same cell, holds; the reverse is counted too.
"""
from matplotlib.patches import Patch

from common import plt, save_figure
from stability_common import FAIL_COLOR, STABLE_COLOR, cell_map
from stability_contact import (GRID_MODES, RELEASE_STYLES, STICK_MARGIN_N, fast_grid, fast_run,
                               release_axis, release_points, release_table)
from stability_explicit import explicit_grid, explicit_limit
from stability_loops import coupling_grid, coupling_point, penalty_grid, penalty_point

TAG = "_p2"
TINY_EDITS = {"body.element": "p2"}
PRESS_EDITS = {"body.element": "p2", "body.mesh.box.cells": [8, 8, 2]}

# Per map of block_press: how a point is named in both runs, and whether it failed.
MAPS = {
    "coupling": (lambda p: (p["mode"], p["k_lin_N_m"], p["visual_hz"]), lambda p: p["unstable"]),
    "penalty": (lambda p: (p["stiffness_N_m"], p["haptic_rate_hz"]), lambda p: p["unstable"]),
    "release": (lambda p: (p["law"], p["mode"], p["visual_hz"]), lambda p: p["sticks"]),
    "fast_tool": (lambda p: (p["mode"], p["youngs_modulus_Pa"], p["press_s"]),
                  lambda p: p["fails"] or p["tunnelled"]),
}


def fast_point(bench, mode, E, press_s):
    bench.progress(f"stability: fast tool{TAG}, {mode}, E {E:g} Pa, press in {press_s:g} s")
    return fast_run(bench, mode, E, press_s, edits=PRESS_EDITS, tag=TAG)


def quadratic_points(bench):
    """The quadratic body's runs of every map, on the linear maps' grids."""
    moduli, tolerance = explicit_grid(bench.quick)
    explicit = [explicit_limit(bench, E, tolerance, TINY_EDITS, TAG) for E in moduli]
    coupling = [coupling_point(bench, mode, k, hz, PRESS_EDITS, TAG)
                for mode, cells in coupling_grid(bench.quick).items() for k, hz in cells]
    penalty = [penalty_point(bench, k, rate, PRESS_EDITS, TAG)
               for k, rate in penalty_grid(bench.quick)]
    release, reference, baseline, baseline_name = release_points(bench, PRESS_EDITS, TAG)
    grid_moduli, times, others, other_times, compare_E = fast_grid(bench.quick)
    fast = [fast_point(bench, mode, E, T)
            for mode in GRID_MODES for E in grid_moduli for T in times]
    fast += [fast_point(bench, mode, compare_E, T) for mode in others for T in other_times]
    return {"explicit": explicit, "coupling": coupling, "penalty": penalty, "release": release,
            "release_reference": reference, "release_baseline_N": baseline,
            "release_baseline": baseline_name, "fast_tool": fast}


def compare(linear_points, quadratic_points, key, failed):
    """Cell by cell: the cells where only the quadratic body fails, and where only the linear."""
    linear = {key(p): failed(p) for p in linear_points}
    new = [key(p) for p in quadratic_points if failed(p) and key(p) in linear
           and not linear[key(p)]]
    gone = [key(p) for p in quadratic_points if not failed(p) and linear.get(key(p), False)]
    unmatched = [key(p) for p in quadratic_points if key(p) not in linear]
    return {"cells": len(quadratic_points),
            "linear_failing": sum(linear.values()),
            "quadratic_failing": sum(failed(p) for p in quadratic_points),
            "new_failing": new, "no_longer_failing": gone, "unmatched": unmatched}


def quadratic_map(bench, linear):
    """`linear`: the results of maps 1–5 (stability.run's dict) on the same grids."""
    runs = quadratic_points(bench)
    comparison = {name: compare(linear[name]["points"], runs[name], key, failed)
                  for name, (key, failed) in MAPS.items()}
    linear_omega = {p["youngs_modulus_Pa"]: p["omega_max_rad_s"]
                    for p in linear["explicit"]["points"]}
    omega_ratios = [p["omega_max_rad_s"] / linear_omega[p["youngs_modulus_Pa"]]
                    for p in runs["explicit"] if p["youngs_modulus_Pa"] in linear_omega]
    figure = quadratic_chart(bench, runs, comparison, linear["explicit"]["points"],
                             linear["release"]["points"])
    return {"tiny_edits": TINY_EDITS, "press_edits": PRESS_EDITS, "points": runs,
            "comparison": comparison, "omega_max_over_linear": omega_ratios}, figure


def release_panel(axis, runs, linear_release, new_cells):
    """The sticking force against the visual rate per law and mode, P2 solid, P1 dashed; red below
    the P2 baseline by more than the margin; rings on the cells where only P2 sticks."""
    baseline = runs["release_baseline_N"]
    measured = [p for p in runs["release"] + linear_release if p["sticking_N"] is not None]
    low = min([p["sticking_N"] for p in measured] + [baseline]) - 0.1
    axis.axhspan(low, baseline - STICK_MARGIN_N, color=FAIL_COLOR, alpha=0.45, lw=0)
    axis.axhline(baseline, color="k", ls="--", lw=1,
                 label=f"P2: {runs['release_baseline'].split(' (')[0]} {baseline:+.3f} N")
    for (law, mode), (color, _) in RELEASE_STYLES.items():
        for points, line, body in ((runs["release"], "-", "P2"), (linear_release, "--", "P1")):
            chosen = sorted((p for p in points if (p["law"], p["mode"]) == (law, mode)
                             and p["sticking_N"] is not None), key=lambda p: p["visual_hz"])
            axis.plot([p["visual_hz"] for p in chosen], [p["sticking_N"] for p in chosen],
                      marker="o" if body == "P2" else ".", ls=line, color=color, lw=1,
                      label=f"{body}: {law} law, --mode {mode}")
    for p in runs["release"]:
        if (p["law"], p["mode"], p["visual_hz"]) in new_cells and p["sticking_N"] is not None:
            axis.plot(p["visual_hz"], p["sticking_N"], "o", ms=13, mfc="none", mec="k")
    axis.plot([], [], "o", ms=10, mfc="none", mec="k", ls="", label="new: sticks on P2 only")
    release_axis(axis, sorted({p["visual_hz"] for p in runs["release"]}), low,
                 "sticking force while lifting (N)",
                 "P2 body: release (sticking force, worst phase; red: sticks)")
    axis.title.set_fontsize(9)
    axis.legend(fontsize=6, loc="lower right")


def quadratic_chart(bench, runs, comparison, linear_explicit, linear_release):
    fig, axes = plt.subplots(2, 4, figsize=(22, 9.6))
    new = {name: set(c["new_failing"]) for name, c in comparison.items()}

    def mark(name, key):
        def text(p):
            marks = ["new"] if key(p) in new[name] else []
            return ", ".join(marks + (["tunnels"] if p.get("tunnelled") else []))
        return text
    panels = [("coupling", "coupling", "visual_hz", "k_lin_N_m", "visual rate (Hz)",
               "coupling stiffness k_lin (N/m)"),
              ("coupling", "linear", "visual_hz", "k_lin_N_m", "visual rate (Hz)",
               "coupling stiffness k_lin (N/m)"),
              ("penalty", "penalty", "haptic_rate_hz", "stiffness_N_m", "haptic rate (Hz)",
               "penalty stiffness k (N/m)"),
              ("fast_tool", "hybrid", "speed_m_s", "youngs_modulus_Pa", "press speed (m/s)",
               "Young's modulus E (Pa)"),
              ("fast_tool", "linear", "speed_m_s", "youngs_modulus_Pa", "press speed (m/s)",
               "Young's modulus E (Pa)")]
    for axis, (name, mode, xkey, ykey, xlabel, ylabel) in zip(axes.flat, panels):
        points = [p for p in runs[name] if p["mode"] == mode]
        if not points:
            axis.set_visible(False)
            continue
        key, failed = MAPS[name]
        value = ((lambda p: f"{1e3 * p['haptic_penetration_m']:.2f}") if name == "fast_tool"
                 else (lambda p: f"{p['oscillation_rms_N']:.3f}"))
        cell_map(axis, points, xkey, ykey, failed, value, mark(name, key))
        axis.set(xlabel=xlabel, ylabel=ylabel,
                 title=f"P2 body, --mode {mode}: "
                       + ("penetration (mm)" if name == "fast_tool" else "oscillation RMS (N)"))
        axis.title.set_fontsize(9)
    release_panel(axes.flat[5], runs, linear_release, new["release"])
    last = axes.flat[6]
    axes.flat[7].set_visible(False)
    for points, label, color in ((linear_explicit, "P1 (linear tets)", "k"),
                                 (runs["explicit"], "P2 (quadratic tets)", "C0")):
        Es = [p["youngs_modulus_Pa"] for p in points]
        last.plot(Es, [p["theory_dt_s"] for p in points], "-", color=color, lw=1,
                  label=f"{label}: 2/ω_max")
        last.plot(Es, [p["measured_dt_s"] for p in points], "o", color=color, mfc="none",
                  label=f"{label}: measured limit")
    last.set(xscale="log", yscale="log", xlabel="Young's modulus E (Pa)",
             ylabel="largest stable explicit dt (s)", title="block_tiny: explicit limit")
    last.grid(True, which="both", alpha=0.3)
    last.legend(fontsize=7)
    axes.flat[0].legend(handles=[Patch(color=STABLE_COLOR, label="stable"),
                                 Patch(color=FAIL_COLOR, label="fails (its map's criterion)")],
                        fontsize=7, loc="upper left")
    save_figure(fig, bench.path("stability_p2.png"))
    return {"file": "stability_p2.png",
            "caption": "Maps 2–5 on a quadratic (P2) block_press, cell by cell as on the linear "
                       "body ('new': fails where the linear body held; 'tunnels': no contact in "
                       "the model while the tool is through; the release at each cell's worst "
                       "phase against the P1 body's forces, dashed, each body's cells judged "
                       "against its own baseline), and "
                       "the explicit limit of block_tiny with both elements "
                       "against each one's 2/ω_max."}


def ratio_text(ratios):
    if not ratios:
        return "(no linear run at that E to compare)"
    low, high = min(ratios), max(ratios)
    return f"{low:.2f} times" if high - low < 0.005 else f"{low:.2f}–{high:.2f} times"


def quadratic_markdown(result):
    c = result["comparison"]
    explicit = result["points"]["explicit"]
    low = min(p["largest_stable_dt_s"] / p["theory_dt_s"] for p in explicit)
    high = max(p["smallest_unstable_dt_s"] / p["theory_dt_s"] for p in explicit)
    total_new = sum(len(x["new_failing"]) for x in c.values())
    md = ["**The maps on a quadratic body** (`body.element: p2`; block_press on an 8 × 8 × 2 "
          "lattice, 1,445 nodes against the linear body's 1,024; each map's own criterion, the "
          f"release against the quadratic body's own baseline, {result['points']['release_baseline']}"
          f" {result['points']['release_baseline_N']:+.3f} N): "
          + (f"**{total_new} new unstable cell{'s' if total_new > 1 else ''}**" if total_new
             else "no new unstable cell")
          + f" in {sum(x['cells'] for x in c.values())}. Explicit Euler on the quadratic "
          f"block_tiny holds up to between {low:.4f} and {high:.4f} × its own 2/ω_max; its ω_max "
          f"is {explicit[0]['omega_max_rad_s']:.0f} rad/s at E {explicit[0]['youngs_modulus_Pa']:g}"
          f" Pa, {ratio_text(result['omega_max_over_linear'])} the linear body's on the same "
          "lattice, and its explicit step that much shorter (the quadratic field's highest mode "
          "has a shorter wavelength). Implicit Euler at 100× stayed bounded in "
          f"{sum(p['implicit_bounded'] for p in explicit)} of {len(explicit)}.", "",
          "| map | cells | failing, P1 | failing, P2 | P2 fails, P1 held | P2 holds, P1 failed |",
          "|---|---:|---:|---:|---|---|"]
    for name, x in c.items():
        def cells(keys):
            return ", ".join("/".join(f"{v:g}" if isinstance(v, float) else str(v) for v in k)
                             for k in keys) or "none"
        md.append(f"| {name} | {x['cells']} | {x['linear_failing']} | {x['quadratic_failing']} | "
                  f"{cells(x['new_failing'])} | {cells(x['no_longer_failing'])} |")
    md += ["", "The release map on the quadratic body: sticking force (N) at the worst phase, in "
           "bold where it sticks against the quadratic body's own baseline, the best phase in "
           "brackets:", ""] + release_table(result["points"]["release"]) + [""]
    return md
