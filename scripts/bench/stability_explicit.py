"""Stability map 1: explicit against implicit integration (issue 12, item 3; see stability.py).

`hapsim fem` on scenes/block_tiny.yaml, undamped: the largest stable explicit step, bisected on dt
per Young's modulus, against the theoretical 2/ω_max of the summary (power iteration,
fem/max_frequency.h); implicit Euler at 100 times that step.

Criterion: a run is unstable if it diverges (non-finite nodes) or its probe moves more than 1 cm (a
fifth of the block) within EXPLICIT_STEPS = 3,000 steps: just above the limit an unstable mode grows
by |λ| = 2.4 a step at 1.1 × 2/ω_max and 1.09 at 1.001 ×, from round-off to metres well within
that. The theory: symplectic Euler's amplification leaves the unit circle once ω_max dt > 2, and the
highest lattice mode (ω_max ∝ √(E/ρ)/h) sets ω_max, so the limit falls as E^−1/2; implicit Euler
damps that mode at any step.
"""
import json
import math
import os

import numpy as np

from common import BenchError, plt, read_csv, save_figure
from stability_common import FAIL_COLOR, finite

BLOCK = "scenes/block_tiny.yaml"
EXPLICIT_STEPS = 3000
EXPLICIT_U_LIMIT_M = 0.01
IMPLICIT_FACTOR = 100.0
IMPLICIT_STEPS = 200


def fem_run(bench, label, E, dt, steps, integrator="explicit", edits=None):
    """One `hapsim fem` run of the undamped block; `edits` (dotted keys, as Bench.scene_variant)
    change it further (the quadratic element: stability_quadratic.py)."""
    scene = bench.scene_variant(BLOCK, {
        "time.dt_s": dt, "time.num_steps": steps, "body.integrator": integrator,
        "body.material.youngs_modulus_Pa": E, "body.material.rayleigh_alpha_1_s": 0.0,
        "body.material.rayleigh_beta_s": 0.0, **(edits or {})}, label)
    folder = os.path.dirname(bench.path("runs", label, "summary.json"))
    for name in ("summary.json", "steps.csv"):   # a diverged run writes neither: no stale reads
        if os.path.exists(os.path.join(folder, name)):
            os.remove(os.path.join(folder, name))
    try:
        bench.hapsim_run("fem", scene, "--out", folder)
    except BenchError as error:
        if "diverged" not in str(error):
            raise
        return {"dt_s": dt, "stable": False, "diverged": True, "max_u_m": None, "summary": None}
    with open(os.path.join(folder, "summary.json")) as f:
        summary = json.load(f)
    max_u = 0.0
    for row in read_csv(os.path.join(folder, "steps.csv")):
        u = math.sqrt(sum(v * v for k, v in row.items() if k.endswith(("_ux_m", "_uy_m", "_uz_m"))))
        max_u = max(max_u, u) if math.isfinite(u) else math.inf
    return {"dt_s": dt, "stable": max_u < EXPLICIT_U_LIMIT_M, "diverged": False,
            "max_u_m": finite(max_u), "summary": summary}


def explicit_limit(bench, E, tolerance, edits=None, tag=""):
    """Bisects the explicit limit at E; `edits` and `tag` as fast_run's (a variant's runs)."""
    name = f"stab_explicit_E{E:g}{tag}"
    bench.progress(f"stability: explicit{tag}, E {E:g} Pa: ω_max")
    first = fem_run(bench, f"{name}_omega", E, 1e-6, 1, edits=edits)
    omega = first["summary"]["omega_max_rad_s"]
    theory = 2.0 / omega  # the scene variant is undamped (rayleigh 0): the plain limit
    # The bracket is checked by runs, not assumed: theory/3 must hold, 5 theory must fail
    # (asymmetric, so that no bisection point sits on the theory by construction).
    lo, hi, runs = theory / 3.0, theory * 5.0, []
    for dt, expected in ((lo, True), (hi, False)):
        bench.progress(f"stability: explicit{tag}, E {E:g} Pa, dt {dt:.4g} s (bracket)")
        run = fem_run(bench, f"{name}_{len(runs):02d}", E, dt, EXPLICIT_STEPS, edits=edits)
        runs.append(run)
        if run["stable"] != expected:
            raise BenchError(f"explicit E {E:g}: dt {dt:g} s ({dt / theory:g} × 2/ω_max) "
                             f"{'failed' if expected else 'held'}; the bracket is wrong")
    while hi / lo > 1.0 + tolerance:
        dt = math.sqrt(lo * hi)
        bench.progress(f"stability: explicit{tag}, E {E:g} Pa, dt {dt:.5g} s "
                       f"({dt / theory:.4f} × 2/ω)")
        run = fem_run(bench, f"{name}_{len(runs):02d}", E, dt, EXPLICIT_STEPS, edits=edits)
        runs.append(run)
        lo, hi = (dt, hi) if run["stable"] else (lo, dt)
    bench.progress(f"stability: implicit{tag}, E {E:g} Pa at {IMPLICIT_FACTOR:g} × the limit")
    implicit = fem_run(bench, f"{name}_implicit", E, IMPLICIT_FACTOR * theory, IMPLICIT_STEPS,
                       "implicit", edits=edits)
    measured = math.sqrt(lo * hi)
    return {"youngs_modulus_Pa": E, "omega_max_rad_s": omega, "theory_dt_s": theory,
            "largest_stable_dt_s": lo, "smallest_unstable_dt_s": hi, "measured_dt_s": measured,
            "measured_over_theory": measured / theory,
            "implicit_dt_s": IMPLICIT_FACTOR * theory, "implicit_steps": IMPLICIT_STEPS,
            "implicit_bounded": implicit["stable"], "implicit_max_u_m": implicit["max_u_m"],
            "runs": [{"dt_s": r["dt_s"], "stable": r["stable"], "diverged": r["diverged"],
                      "max_u_m": r["max_u_m"]} for r in runs]}


def explicit_grid(quick):
    """The moduli mapped and the bisection's relative tolerance."""
    return ([5e4], 0.02) if quick else ([1e4, 3e4, 1e5, 3e5, 1e6, 3e6, 1e7], 0.002)


def explicit_map(bench):
    moduli, tolerance = explicit_grid(bench.quick)
    points = [explicit_limit(bench, E, tolerance) for E in moduli]
    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.6),
                                      gridspec_kw={"width_ratios": [1.6, 1]})
    Es = [p["youngs_modulus_Pa"] for p in points]
    top = max(p["implicit_dt_s"] for p in points) * 3
    # Between the moduli the curves follow dt ∝ E^−1/2 (interpolated in dt·√E; beyond the ends,
    # extended with that slope), so one modulus (quick) still draws a line and a region.
    grid = np.geomspace(min(Es) / 2, max(Es) * 2, 200)

    def along(key):
        scaled = [p[key] * math.sqrt(p["youngs_modulus_Pa"]) for p in points]
        return np.interp(np.log(grid), np.log(Es), scaled) / np.sqrt(grid)

    left.fill_between(grid, along("measured_dt_s"), top, color=FAIL_COLOR, alpha=0.8, lw=0,
                      label="explicit Euler diverges (measured)")
    left.plot(grid, along("theory_dt_s"), "k-", lw=1.2, label="theory: 2 / ω_max (power iteration)")
    left.errorbar(Es, [p["measured_dt_s"] for p in points],
                  yerr=[[p["measured_dt_s"] - p["largest_stable_dt_s"] for p in points],
                        [p["smallest_unstable_dt_s"] - p["measured_dt_s"] for p in points]],
                  fmt="o", color="C3", ms=6, mfc="none", label="measured largest stable dt")
    for bounded in (True, False):
        chosen = [p for p in points if p["implicit_bounded"] == bounded]
        if chosen:
            left.plot([p["youngs_modulus_Pa"] for p in chosen],
                      [p["implicit_dt_s"] for p in chosen],
                      "s" if bounded else "X", color="C2" if bounded else "r", ms=7,
                      label=f"implicit Euler at {IMPLICIT_FACTOR:g}× 2/ω_max: "
                            + ("bounded" if bounded else "NOT bounded"))
    left.set(xscale="log", yscale="log", xlabel="Young's modulus E (Pa)", ylabel="time step dt (s)",
             xlim=(grid[0], grid[-1]), ylim=(min(p["theory_dt_s"] for p in points) / 5, top),
             title=f"block_tiny, undamped: largest stable step ({EXPLICIT_STEPS} steps)")
    left.legend(fontsize=7, loc="lower left")
    right.errorbar(Es, [100 * (p["measured_over_theory"] - 1) for p in points],
                   yerr=[[100 * (p["measured_dt_s"] - p["largest_stable_dt_s"]) / p["theory_dt_s"]
                          for p in points],
                         [100 * (p["smallest_unstable_dt_s"] - p["measured_dt_s"])
                          / p["theory_dt_s"]
                          for p in points]], fmt="o", color="C3", mfc="none")
    right.axhline(0, color="k", lw=1)
    right.set(xscale="log", xlim=(grid[0], grid[-1]), xlabel="Young's modulus E (Pa)",
              ylabel="measured limit / (2/ω_max) − 1 (%)",
              title="measured against theory (bar: bisection bracket)")
    for axis in (left, right):
        axis.grid(True, which="both", alpha=0.3)
    save_figure(fig, bench.path("stability_explicit.png"))
    figure = {"file": "stability_explicit.png",
              "caption": "Explicit against implicit integration: the largest stable explicit step "
                         "against Young's modulus (bisection), the theoretical 2/ω_max, the "
                         "diverging region shaded, and implicit Euler at 100× that step."}
    return {"scene": BLOCK, "steps": EXPLICIT_STEPS, "unstable_if": "diverged or probe moves > "
            f"{EXPLICIT_U_LIMIT_M} m", "bisection_tolerance": tolerance, "points": points}, figure


def explicit_markdown(result):
    points = result["points"]
    low = min(p["largest_stable_dt_s"] / p["theory_dt_s"] for p in points)
    high = max(p["smallest_unstable_dt_s"] / p["theory_dt_s"] for p in points)
    md = [f"**Explicit against implicit** (`hapsim fem` on {BLOCK}, no damping; unstable: diverged "
          f"or the probe moved more than {100 * EXPLICIT_U_LIMIT_M:g} cm within "
          f"{result['steps']} steps; bisection to {100 * result['bisection_tolerance']:g} %). "
          f"At every E the limit lies between {low:.4f} and {high:.4f} × 2/ω_max (the largest "
          "stable and the first unstable step), so theory and measurement agree to "
          f"{100 * max(1 - low, high - 1):.2f} %; it falls as E^−1/2 (the sweep is self-similar: "
          "K ∝ E, so every E bisects to the same ratio). Implicit Euler at "
          f"{IMPLICIT_FACTOR:g}× that step stayed bounded in "
          f"{sum(p['implicit_bounded'] for p in points)} of {len(points)}. Why: symplectic Euler's "
          "amplification leaves the unit circle once ω_max dt > 2, and the highest lattice mode "
          "(ω_max ∝ √(E/ρ)/h) sets ω_max; implicit Euler damps that mode at any step.", "",
          "| E (Pa) | ω_max (rad/s) | 2/ω_max (s) | largest stable dt (s) | "
          "first unstable dt (s) | "
          "measured / theory | implicit at 100× |", "|---:|---:|---:|---:|---:|---:|---|"]
    for p in points:
        md.append(f"| {p['youngs_modulus_Pa']:g} | {p['omega_max_rad_s']:.0f} | "
                  f"{p['theory_dt_s']:.4g} | {p['largest_stable_dt_s']:.4g} | "
                  f"{p['smallest_unstable_dt_s']:.4g} | {p['measured_over_theory']:.4f} | "
                  + ("bounded" if p["implicit_bounded"] else "**not bounded**")
                  + (f", max |u| {1e3 * p['implicit_max_u_m']:.2f} mm"
                     if p["implicit_max_u_m"] is not None else "") + " |")
    md.append("")
    return md
