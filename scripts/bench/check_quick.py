#!/usr/bin/python3
"""Checks the JSON of `scripts/bench.sh --quick` (ctest: bench_quick_test), each against a value
the bench did not produce:

- every experiment ran and every number in the results is finite (no NaN, no infinity);
- modes: the reference has zero model age (every step is a full frame), and the paper's linear
  model renders the device force closer to the reference than standard coupling at the same rate;
- indentation: the Hertz and punch coefficients are stiffer than the closed forms (a conforming
  displacement FEM, and a block bonded at its base, are stiffer than the half-space: error > 0)
  and within the quick meshes' band (Hertz < 50 %, punch < 90 %), falling with refinement (and
  the frame cost at which the linear front reaches an error, behind RESULTS.md's "a third of P1's
  error would take...", giving back the cost that error_at_cost gave that error); the
  quadratic tets on 8x fewer tets than the coarsest linear lattice also stiffer than the closed
  form, but less stiff than that lattice; the punch on the rim-following lattice (nodes only)
  within 25 % of the bonded layer's coefficient;
- punch_rim, hertz_disk: the punch on meshes graded to its rim stiffer than the bonded layer by
  under 40 % with either element, the sphere on meshes graded from its contact zone by under 60 %,
  the quadratic mesh nearer to it in both, and nearer still on the punch with quarter-point nodes
  at the rim;
- cantilever: the small-load tip deflection of the finest quick mesh within 15 % of beam theory,
  and the linear element law missing the large-load axial shortening that the corotational one
  captures;
- stability: the measured explicit limit within 2 % of 2/ω_max, and implicit Euler bounded at
  100 times that step, with linear and with quadratic tets; the release cells' phases of the frame
  clock the same for the lcp mode (it re-solves every step) and apart for the linear mode (its
  frozen contacts pull for the rest of a frame);
- economy: per scene, the chosen configuration's RMS device-force error against the finest run,
  recomputed here from the two runs' haptic.csv, within the tolerance recomputed from the finest
  run's peak (max(5 %, 0.05 N)); the finest configuration run a second time gives the same force
  history (the comparison of configurations rests on it), and its run with a perturbed stiffness
  is there, its reported difference recomputed; and at least one knob moved.

Usage: scripts/bench/check_quick.py OUT_DIR/results.json
"""
import csv
import json
import math
import os
import sys

import yaml

import indentation

EXPECTED = ["indentation", "punch_rim", "hertz_disk", "modes", "cantilever", "stability", "economy"]


def finite_everywhere(value, path, problems):
    if isinstance(value, float) and not math.isfinite(value):
        problems.append(f"{path} is {value}")
    elif isinstance(value, dict):
        for key, item in value.items():
            finite_everywhere(item, f"{path}.{key}", problems)
    elif isinstance(value, list):
        for i, item in enumerate(value):
            finite_everywhere(item, f"{path}[{i}]", problems)


def check_graded(experiment, what, band, quarter_point=False):
    """A press on Gmsh meshes graded towards its contact (punch_rim, hertz_disk): a conforming FEM
    whose contact ends where the tool's does is stiffer than the bonded layer, within the quick
    meshes' band; the quadratic mesh, on a fifth to a quarter of the tets, nearer to it than the
    linear one; and the punch's quadratic mesh with quarter-point nodes at the rim nearer than
    the same mesh without (punch_rim.py: they hold the rim's √ρ field), where quarter_point
    says the experiment has them."""
    problems = []
    errors = {(r["element"], r["variant"]): r["layer_relative_error"] for r in experiment["runs"]}
    for (element, variant), error in errors.items():
        if not 0.0 < error < band:
            problems.append(f"{what}, {element} {variant}: {error:+.3f} against the bonded layer, "
                            f"outside (0, {band:+.0%})")
    plain = {element: error for (element, variant), error in errors.items()
             if variant != "quarter"}
    if not plain.get("p2", 1.0) < plain.get("p1", 0.0):
        problems.append(f"{what}: P2 {plain.get('p2')} not nearer the bonded layer than P1 "
                        f"{plain.get('p1')}")
    quarter = errors.get(("p2", "quarter"))
    if quarter_point and quarter is None:
        problems.append(f"{what}: no quadratic run with quarter-point nodes")
    elif quarter_point and not quarter < plain.get("p2", 0.0):
        problems.append(f"{what}: P2 with quarter-point nodes {quarter:+.3f} not nearer the "
                        f"bonded layer than without {plain.get('p2')}")
    return problems


def check(results, results_dir):
    problems = []
    experiments = results["experiments"]
    for name in EXPECTED:
        if name not in experiments:
            problems.append(f"experiment {name} did not run")
    finite_everywhere(experiments, "experiments", problems)
    if problems:
        return problems

    modes = experiments["modes"]
    if modes["reference"]["max_model_age_s"] != 0.0:
        problems.append(f"reference model age {modes['reference']['max_model_age_s']} s, not 0")
    for hz in sorted({r["visual_hz"] for r in modes["runs"]}):
        error = {r["mode"]: r["rms_error_N"] for r in modes["runs"] if r["visual_hz"] == hz}
        if not error["linear"] < error["coupling"]:
            problems.append(f"modes at {hz:g} Hz: linear {error['linear']:.4f} N does not beat "
                            f"coupling {error['coupling']:.4f} N")

    for name, band in (("hertz", 0.5), ("punch", 0.9)):
        # The punch's other ways of contact (nodes only; on the rim-following lattice) are not in
        # this band: their error may have either sign.
        every = [r for r in experiments["indentation"][name]["runs"] if r["variant"] == "features"]
        runs = sorted((r for r in every if r["element"] == "p1"), key=lambda r: r["tets"])
        # Quadratic tets on 8x fewer tets than the coarsest linear lattice: less stiff than it,
        # and still stiffer than the closed form (issue 27).
        quadratic = [r for r in every if r["element"] == "p2"]
        if not quadratic or not 0.0 < quadratic[0]["relative_error"] < runs[0]["relative_error"]:
            problems.append(f"{name}: quadratic tets' error "
                            f"{[round(r['relative_error'], 3) for r in quadratic]} not in (0, the "
                            f"coarsest linear lattice's {runs[0]['relative_error']:+.3f})")
        finest = runs[-1]["relative_error"]
        if not 0.0 < finest < band:
            problems.append(f"{name}: error {finest:+.3f} at the finest quick mesh, not in (0, "
                            f"{band})")
        if not runs[-1]["relative_error"] < runs[0]["relative_error"]:
            problems.append(f"{name}: error does not fall with refinement: "
                            f"{[round(r['relative_error'], 3) for r in runs]}")
        problems += check_cost_at_error(runs, name)

    # The punch on the rim-following lattice, nodes only: its footprint is the punch's, so its
    # coefficient is within a quarter of the bonded layer's (a conforming FEM's excess, either sign
    # from the rim polygon's missing area).
    for r in experiments["indentation"]["punch"]["runs"]:
        if r["variant"] == "rim" and not abs(r["layer_relative_error"]) < 0.25:
            problems.append(f"punch on the rim-following lattice: {r['layer_relative_error']:+.3f} "
                            "against the bonded layer, not within 25 %")

    problems += check_graded(experiments["punch_rim"], "punch on the rim-graded meshes", 0.4,
                             quarter_point=True)
    problems += check_graded(experiments["hertz_disk"], "sphere on the disk-graded meshes", 0.6)

    cantilever = experiments["cantilever"]["runs"]
    along_x = [r for r in cantilever if r["orientation"] == "x" and r["element"] == "p1"]
    small = max((r for r in along_x if r["load"] == "small"), key=lambda r: r["n"])
    if not abs(small["vertical_error"]) < 0.15:
        problems.append(f"cantilever: small-load error {small['vertical_error']:+.3f} at "
                        f"{small['cells']}, not within 15 % of beam theory")
    large = {r["elasticity"]: r for r in along_x if r["load"] == "large" and r["n"] == small["n"]}
    if not (abs(large["linear"]["axial_error"]) > 0.9 > abs(large["corotational"]["axial_error"])
            + 0.5):
        problems.append("cantilever: axial shortening at large load not missed by linear "
                        f"({large['linear']['axial_error']:+.2f}) and caught by corotational "
                        f"({large['corotational']['axial_error']:+.2f})")

    for name, c in experiments["stability"]["quadratic"]["comparison"].items():
        if c["unmatched"]:
            problems.append(f"quadratic {name} map: cells with no linear run {c['unmatched']}")
    for point in (experiments["stability"]["explicit"]["points"]
                  + experiments["stability"]["quadratic"]["points"]["explicit"]):
        if not abs(point["measured_over_theory"] - 1.0) < 0.02:
            problems.append(f"explicit limit {point['measured_over_theory']:.4f} x 2/omega_max at "
                            f"E = {point['youngs_modulus_Pa']:g} Pa")
        if not point["implicit_bounded"]:
            problems.append(f"implicit Euler unbounded at {point['implicit_dt_s']:g} s")
    problems += check_release_phases(experiments["stability"]["release"]["points"])
    problems += check_economy(experiments["economy"], results_dir)
    return problems


def check_cost_at_error(p1_runs, name):
    """indentation.cost_at_error (the frame at which P1's front reaches an error: RESULTS.md's
    'a third of P1's error would take...') against error_at_cost, the interpolation it inverts:
    back to the same cost between two front runs; below the cheapest, flagged extrapolated."""
    problems = []
    for nu in sorted({r["poisson_ratio"] for r in p1_runs}):
        problems += check_cost_at_error_at(
            [r for r in p1_runs if r["poisson_ratio"] == nu], f"{name} at ν {nu:g}")
    return problems


def check_cost_at_error_at(p1_runs, name):
    key = "layer_relative_error"
    front = indentation.pareto_front(p1_runs, key)
    problems = []
    for (c0, _), (c1, _) in zip(front, front[1:]):
        cost = math.sqrt(c0 * c1)
        error = indentation.error_at_cost(p1_runs, cost, key)
        back = indentation.cost_at_error(p1_runs, error, key)
        if back is None or abs(back[0] / cost - 1.0) > 1e-9 or back[1]:
            problems.append(f"{name}: cost_at_error gives {back} for the error at {cost:.4g} ms")
    if len(front) >= 2:
        back = indentation.cost_at_error(p1_runs, 1.1 * abs(front[0][1]), key)
        if back is None or not back[0] < front[0][0] or not back[1]:
            problems.append(f"{name}: cost_at_error gives {back} above the cheapest run's error")
    return problems


def check_release_phases(points):
    """The release cells run at several phases of the frame clock. The lcp mode re-solves the
    unilateral problem every haptic step, so where the frame clock falls cannot matter to it:
    its phases within 0.01 N. The paper's linear mode holds the frame's contacts until the next
    frame, pulling at the coupling's k v_lift (1000 N/m × 11 mm/s) for however much of a frame is
    left after they turn to tension, so its phases must differ at the low rates: by more than the
    map's margin, 0.05 N, up to 25 Hz, where half a frame of that pull is 0.22 N or more (the quick
    map has 20 Hz; at 200 Hz the full map's phases are 0.6 ms apart, under a haptic step)."""
    problems = []
    for p in points:
        phases = [x for x in p.get("phase_sticking_N", []) if x is not None]
        if len(phases) < 2:
            problems.append(f"release {p['law']}/{p['mode']} at {p['visual_hz']:g} Hz: "
                            f"{len(phases)} finite phases, not several")
            continue
        spread = max(phases) - min(phases)
        if p["mode"] == "lcp" and not spread < 0.01:
            problems.append(f"release lcp at {p['visual_hz']:g} Hz: phases {spread:.3f} N apart")
        if p["mode"] == "linear" and p["visual_hz"] <= 25.0 and not spread > 0.05:
            problems.append(f"release {p['law']}/linear at {p['visual_hz']:g} Hz: phases only "
                            f"{spread:.3f} N apart (is the script shifted?)")
    return problems


def device_forces(folder):
    """{t_s: (Fx, Fy, Fz)} of a run's haptic.csv, read here (not with the bench's reader)."""
    with open(os.path.join(folder, "haptic.csv")) as f:
        return {row["t_s"]: tuple(float(row[f"force_{a}_N"]) for a in "xyz")
                for row in csv.DictReader(f)}


def youngs_moduli(results_dir, folder):
    """Every youngs_modulus_Pa in the scene file of the run in `folder` (runs/NAME: the bench wrote
    its scene as scenes/NAME.yaml), in the file's order."""
    with open(os.path.join(results_dir, "scenes", os.path.basename(folder) + ".yaml")) as f:
        scene = yaml.safe_load(f)
    found = []

    def walk(node):
        if isinstance(node, dict):
            for key, value in node.items():
                if key == "youngs_modulus_Pa":
                    found.append(value)
                else:
                    walk(value)
        elif isinstance(node, list):
            for value in node:
                walk(value)
    walk(scene)
    return found


def check_economy(economy, results_dir):
    """The chosen run's error recomputed from the two runs' haptic.csv, step by step matched on
    time, against the tolerance recomputed from the finest run's own peak; the finest's repeat
    equal to it; its perturbed run's difference recomputed; and the search moved at least one knob
    on the quick scene."""
    problems = []
    if not economy["scenes"]:
        problems.append("economy: no scene ran")
    fraction, floor_N = economy["tolerance"]["fraction_of_peak"], economy["tolerance"]["floor_N"]
    for name, scene in economy["scenes"].items():
        finest = device_forces(os.path.join(results_dir, scene["finest"]["folder"]))
        chosen = device_forces(os.path.join(results_dir, scene["chosen"]["folder"]))
        repeat = device_forces(os.path.join(results_dir, scene["finest_repeat"]["folder"]))
        peak_N = max(math.hypot(*f) for f in finest.values())
        tolerance_N = max(fraction * peak_N, floor_N)
        if set(chosen) != set(finest):
            problems.append(f"economy: {name}: the chosen run's steps are not the finest's")
            continue
        rms_N = math.sqrt(sum(math.dist(chosen[t], finest[t]) ** 2 for t in finest) / len(finest))
        if not rms_N <= tolerance_N:
            problems.append(f"economy: {name}: chosen RMS error {rms_N:.4f} N outside the "
                            f"tolerance {tolerance_N:.4f} N")
        if not math.isclose(rms_N, scene["chosen"]["rms_error_N"], rel_tol=1e-6, abs_tol=1e-12):
            problems.append(f"economy: {name}: chosen RMS error recomputed {rms_N:.6f} N, reported "
                            f"{scene['chosen']['rms_error_N']:.6f} N")
        if repeat != finest:
            problems.append(f"economy: {name}: the finest configuration run twice gave two force "
                            "histories (the runs are not deterministic)")
        # The perturbed run (every Young's modulus slightly larger): the moduli its scene file
        # holds against the finest's times its scale, and its reported sensitivity recomputed from
        # its own haptic.csv.
        perturbed = scene.get("finest_perturbed")
        if scene["fem_built"] and (not perturbed or "failed" in perturbed):
            problems.append(f"economy: {name}: no perturbed run of the finest configuration"
                            + (f" ({perturbed['failed']})" if perturbed else ""))
        elif perturbed:
            moduli = [youngs_moduli(results_dir, scene[k]["folder"])
                      for k in ("finest", "finest_perturbed")]
            if not moduli[0] or len(moduli[0]) != len(moduli[1]) or not all(
                    math.isclose(b, a * perturbed["youngs_scale"], rel_tol=1e-15)
                    and b != a for a, b in zip(*moduli)):
                problems.append(f"economy: {name}: the perturbed run's Young's moduli {moduli[1]} "
                                f"are not the finest's {moduli[0]} times "
                                f"{perturbed['youngs_scale']!r}")
            moved = device_forces(os.path.join(results_dir, perturbed["folder"]))
            if set(moved) != set(finest):
                problems.append(f"economy: {name}: the perturbed run's steps are not the finest's")
            else:
                moved_N = math.sqrt(sum(math.dist(moved[t], finest[t]) ** 2 for t in finest)
                                    / len(finest))
                if not math.isclose(moved_N, perturbed["rms_error_N"], rel_tol=1e-6,
                                    abs_tol=1e-12):
                    problems.append(f"economy: {name}: perturbed RMS recomputed {moved_N:.3g} N, "
                                    f"reported {perturbed['rms_error_N']:.3g} N")
        if scene["chosen"]["changed"] == "nothing":
            problems.append(f"economy: {name}: no knob moved from the finest configuration")
    return problems


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    with open(sys.argv[1]) as f:
        results = json.load(f)
    problems = check(results, os.path.dirname(os.path.abspath(sys.argv[1])))
    for problem in problems:
        print(f"check_quick: {problem}", file=sys.stderr)
    if problems:
        sys.exit(1)
    print(f"check_quick: {len(EXPECTED)} experiments ran in {results['wall_s']:.0f} s; all checks "
          "hold")


if __name__ == "__main__":
    main()
