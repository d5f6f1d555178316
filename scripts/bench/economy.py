"""Model no more than a scene needs: the cheapest configuration per scene (issue 12, item 4).

For every shipped scene with a tool and a scripted device, the finest configuration is run first:
the scene's deformable mesh refined, corotational elasticity, the exact contact compliance, the
scene's contact law and a visual rate of 100 Hz (or the scene's own, if higher), in the
scene's haptic mode (linear, the paper's; the probe keeps its god-object). Then one knob at a time
is moved from there towards the cheaper end:

- mesh (size and element order, issue 27): linear tets (p1) on the lattice at 0.5, 0.75 and 1
  times the shipped cells per axis (an ellipsoid's or a filled surface's cell size divided by the
  factor), and quadratic tets (p2) at 0.5 times the shipped cells and at half the finest's; a file
  mesh stays as shipped (and linear);
- element law: linear against corotational;
- contact compliance: warped (precomputed at rest, rotated) against exact (forward and backward
  solves on the contact dofs' reach, fem/inverse_quadratic_form.h);
- contact law: equality against unilateral where the scene allows it (not with rigid objects);
  friction only where the scene already has it;
- visual rate: 10, 20, 25, 50, 100 Hz and the scene's own, each a divisor of the haptic rate.

The finest mesh is quadratic, at half the finest linear cells (the same nodes as linear tets at the
finest cells): the indentation and cantilever experiments measure quadratic tets 3-10 times closer
to the closed forms than linear ones at equal cost, and linear tets lock at the tissues' Poisson
ratios (+15 % at 0.45), so a finest linear mesh would hold the sweep to its own stiffness.

The error of a run is the RMS (and max) of |F − F_finest| over every haptic step of the device
force (scripts/compare_modes.py's measure); its cost the visual process's compute per simulated
second, median frame × visual rate (ms/s), as in modes.py; the mean frame's, which counts the
frames in contact fully even where they are a minority, is kept beside it. A knob takes its
cheapest value whose error stays within the tolerance, RMS ≤ max(5 % of the finest run's peak
device force, 0.05 N); the knobs' choices are then run together and checked against the same
tolerance. Where they add up past it, the knob with the largest error of its own steps one value
back towards the finest, and the combination is run again.

The finest configuration is run again as it is (a configuration must give one force history) and,
in a scene with FEM, once more with every Young's modulus 1 + 1e-12 times as large (PERTURBATION).
Where that far smaller change moves the force history by more than the tolerance, the scene's
history is not well posed (a contact that flips on rounding sends it elsewhere) and its knobs'
errors do not rank its configurations: the report says so.

Rigid-only scenes (peg_in_hole, probe_on_tray) build no FEM: only the visual rate (and a contact
law their rigid objects allow) is a knob there.
"""
import copy
import glob
import math
import os
import sys
import time

import yaml

from common import REPO, BenchError, rate_text
from economy_report import chart, markdown

sys.path.insert(0, os.path.join(REPO, "scripts"))
from compare_modes import errors, read_forces  # noqa: E402

# haptic.mode when a scene does not say (device/haptic_mode.h kDefaultHapticMode).
DEFAULT_MODE = "hybrid"

# Bench-only scenes: measured by their own experiments (indentation, cantilever) or scripts
# (block_press_friction, block_press_large), not swept here.
BENCH_ONLY = {"hertz_indentation": "bench-only (the indentation experiment's Hertz press)",
              "flat_punch": "bench-only (the indentation experiment's Boussinesq press)",
              "cantilever": "bench-only (the cantilever experiment; no tool)",
              "block_press_friction": "block_press with the friction law (issue 13), measured "
                                      "against its reference in docs/CONTACT.md: its frame's "
                                      "friction sweeps take ~150 ms, past the sweeps' budget",
              "block_press_large": "block_press on the 28,800-tet block (issue 13): a speed "
                                   "scene, measured by scripts/bench_speed.sh; its finest "
                                   "variant here (~97k tets) would not fit the bench's budget"}
# Per scene: the finest mesh's factor (cells × f; an ellipsoid's cell size / f) and a shortened
# script (time.num_steps) where the full one would not fit the bench's budget; why, for the page.
PLAN = {
    "block_press": {"fine": 1.5},
    "liver_palpation": {"fine": 1.25, "num_steps": 175,
                        "why": "first palpation only (3.5 s: settle, press, 0.5 s hold); "
                               "finest linear cell 6.4 mm (8 / 1.25: at 8 / 1.5 one run took "
                               "3.5 min), finest quadratic 12.8 mm"},
    "polyp": {"fine": 1.5, "num_steps": 450,
              "why": "4.5 s (side push, hold, lift, back down; the withdrawal cut)"},
    "probe": {"fine": 1.5},
    "pick_and_place": {"fine": 1.5},
    "two_organs": {"fine": 1.0, "num_steps": 210,
                   "why": "the liver's palpation only (4.2 s: press, hold, lift); the shipped "
                          "cells the finest linear ones (two surfaces filled with tets), twice "
                          "them the finest quadratic"},
}
QUICK_PLAN = {"block_press": {"fine": 1.0, "num_steps": 40, "visual_hz": 100.0,
                              "knobs": ["compliance", "visual_hz"], "rates": [25.0],
                              "why": "quick: 1.2 s (rest and press), quadratic tets at half "
                                     "the shipped cells, 100 Hz finest, two knobs"}}
MESH_FACTORS = [0.5, 0.75, 1.0]
# Quadratic tets at these factors and at half the finest linear one (the finest mesh of all).
QUADRATIC_MESH_FACTORS = [0.5]
# The finest rate is 100 Hz, not the 200 Hz a 1 kHz haptic rate allows: on block_press the linear
# model is 0.011 N RMS from the 1 kHz reference at 100 Hz (the modes experiment), a fifth of the
# smallest tolerance here (0.05 N), and 200 Hz would double the cost of every run but the rate
# sweep's.
RATES_HZ = [10.0, 20.0, 25.0, 50.0, 100.0]
TOLERANCE_FRACTION, TOLERANCE_FLOOR_N = 0.05, 0.05
# The finest configuration is run once more with every Young's modulus 1 + PERTURBATION times as
# large: a change of about ten thousand roundings, far below any knob's. How far that moves the
# force history is the scene's own sensitivity (the polyp's was 0.08 N, against a 0.05 N
# tolerance: docs/BENCHMARKS.md); errors of that size do not rank configurations.
PERTURBATION = 1e-12
MAX_BACKOFFS = 3
KNOBS = ["mesh", "elasticity", "compliance", "law", "visual_hz"]


# ---------------------------------------------------------------------------- the scenes

def load(path):
    with open(os.path.join(REPO, path)) as f:
        return yaml.safe_load(f)


def first_deformable(scene):
    """The mapping of the scene's first deformable object (body, or objects[i].deformable)."""
    if "body" in scene:
        return scene["body"]
    for item in scene.get("objects", []):
        if "deformable" in item:
            return item["deformable"]
    return None


def mesh_kind(mesh):
    """Which of a scene's mesh sources a deformable object uses: box, ellipsoid, surface or file."""
    kind = next((k for k in ("box", "ellipsoid", "surface", "file") if k in mesh), None)
    if kind is None:
        raise RuntimeError(f"economy: a mesh source it does not know: {sorted(mesh)}")
    return kind


def has_rigid_objects(scene):
    return any("rigid" in item for item in scene.get("objects", []))


def select_scenes(quick):
    """(scene name → spec) for every runnable scene; (name → why) for those skipped."""
    runnable, skipped = {}, {}
    for path in sorted(glob.glob(os.path.join(REPO, "scenes", "*.yaml"))):
        name = os.path.splitext(os.path.basename(path))[0]
        scene = load(os.path.relpath(path, REPO))
        if name in BENCH_ONLY:
            skipped[name] = BENCH_ONLY[name]
        elif "tool" not in scene or not scene.get("device", {}).get("trajectory"):
            skipped[name] = "no tool or device script (an FEM-only scene)"
        elif quick and name not in QUICK_PLAN:
            skipped[name] = "not in the quick run"
        else:
            runnable[name] = spec_for(name, os.path.relpath(path, REPO), scene,
                                      (QUICK_PLAN if quick else PLAN).get(name, {"fine": 1.5}))
    return runnable, skipped


def mesh_value(element, factor):
    """The mesh knob's value: element order and cell factor, e.g. 'p2 0.75'."""
    return f"{element} {factor:g}"


def parse_mesh(value):
    element, factor = value.split()
    return element, float(factor)


def mesh_values(kind, fine):
    """The mesh knob's values, from the fewest nodes to the most (quadratic tets at f hold about
    the nodes of linear ones at 2 f; of equal nodes the quadratic is the finer)."""
    if kind == "file":
        return [mesh_value("p1", 1.0)]
    linear = [("p1", f) for f in sorted(set(MESH_FACTORS + [fine])) if f <= fine]
    quadratic = [("p2", f) for f in sorted(set(QUADRATIC_MESH_FACTORS + [fine / 2]))
                 if f <= fine / 2]
    ordered = sorted(linear + quadratic,
                     key=lambda m: (m[1] * (2 if m[0] == "p2" else 1), m[0] == "p2"))
    return [mesh_value(*m) for m in ordered]


def divides(haptic_hz, hz):
    ratio = haptic_hz / hz
    return ratio >= 1.0 and abs(ratio - round(ratio)) < 1e-9


def spec_for(name, path, scene, plan):
    """What can vary in a scene, in order from the cheapest value to the finest's."""
    haptic_hz = float(scene.get("haptic", {}).get("rate_hz", 1000.0))
    own_hz = 1.0 / float(scene["time"]["dt_s"])
    body = first_deformable(scene)
    kind = None
    if body is not None:
        kind = mesh_kind(body["mesh"])
    law = scene.get("contact", {}).get("law", "unilateral")
    rates = sorted({hz for hz in RATES_HZ + [own_hz] if divides(haptic_hz, hz)})
    finest_hz = plan.get("visual_hz", rates[-1])
    rates = [hz for hz in rates if hz <= finest_hz]
    if "rates" in plan:
        rates = sorted({hz for hz in plan["rates"] if divides(haptic_hz, hz) and hz < finest_hz}
                       | {finest_hz})
    values = {"visual_hz": rates}
    if body is not None:
        values["mesh"] = mesh_values(kind, plan.get("fine", 1.5))
        values["elasticity"] = ["linear", "corotational"]
        values["compliance"] = ["warped", "exact"]
    laws = [law]
    if law == "friction":
        laws = ["unilateral", "friction"]
    elif law == "unilateral" and not has_rigid_objects(scene):
        laws = ["equality", "unilateral"]
    values["law"] = laws
    knobs = [k for k in KNOBS if k in values and len(values[k]) > 1]
    if "knobs" in plan:
        knobs = [k for k in knobs if k in plan["knobs"]]
    finest = {k: v[-1] for k, v in values.items()}
    mode = scene.get("haptic", {}).get("mode", DEFAULT_MODE)
    return {"name": name, "path": path, "scene": scene, "plan": plan, "values": values,
            "knobs": knobs, "finest": finest, "mesh_kind": kind, "fem": body is not None,
            "mode": DEFAULT_MODE if mode == "reference" else mode, "num_steps": plan.get("num_steps"),
            "duration_s": float(scene["time"]["dt_s"]) * (plan.get("num_steps")
                                                         or scene["time"]["num_steps"])}


def scaled_mesh(mesh, kind, factor):
    mesh = copy.deepcopy(mesh)
    if kind == "box":
        mesh["box"]["cells"] = [max(1, round(c * factor)) for c in mesh["box"]["cells"]]
    elif kind == "ellipsoid":
        mesh["ellipsoid"]["cell_size_m"] = mesh["ellipsoid"]["cell_size_m"] / factor
    elif kind == "surface":  # the user's surface filled with tets at that size (Gmsh, cached)
        mesh["cell_size_m"] = mesh["cell_size_m"] / factor
        if "refine" in mesh:
            mesh["refine"]["cell_size_m"] = mesh["refine"]["cell_size_m"] / factor
    return mesh


def mesh_label(spec, value):
    if not spec["fem"]:
        return "no FEM"
    element, factor = parse_mesh(value)
    mesh = scaled_mesh(first_deformable(spec["scene"])["mesh"], spec["mesh_kind"], factor)
    order = element.upper()
    if spec["mesh_kind"] == "box":
        return f"{order} " + "×".join(str(c) for c in mesh["box"]["cells"])
    if spec["mesh_kind"] == "ellipsoid":
        return f"{order} h {1e3 * mesh['ellipsoid']['cell_size_m']:.3g} mm"
    if spec["mesh_kind"] == "surface":
        return f"{order} h {1e3 * mesh['cell_size_m']:.3g} mm"
    return "as shipped"


def absolute(path):
    """A scene's mesh file, relative to scenes/, made absolute (variants live elsewhere)."""
    return path if os.path.isabs(path) else os.path.join(REPO, "scenes", path)


def variant_mesh(mesh, factor):
    """A deformable object's mesh scaled by factor, its file (if any) made absolute."""
    mesh = scaled_mesh(mesh, mesh_kind(mesh), factor)
    for key in ("file", "surface"):
        if key in mesh:
            mesh[key] = absolute(mesh[key])
    return mesh


def variant_body(body, mesh, youngs_scale=1.0):
    """A deformable object with its mesh scaled, its element order set (the mesh knob's value),
    every surface file it names made absolute, and its Young's modulus times youngs_scale."""
    element, factor = parse_mesh(mesh)
    body = copy.deepcopy(body)
    if youngs_scale != 1.0:
        body["material"]["youngs_modulus_Pa"] *= youngs_scale
    body["mesh"] = variant_mesh(body["mesh"], factor)
    if element != "p1" or "element" in body:
        body["element"] = element
    for key in ("visual", "collision"):
        if key in body:
            body[key]["file"] = absolute(body[key]["file"])
    return body


def edits_for(spec, config, youngs_scale=1.0):
    """The scene edits of a configuration (mesh, element law, contact law, a shorter script), and
    every deformable's Young's modulus times youngs_scale (PERTURBATION)."""
    scene = spec["scene"]
    edits = {}
    if spec["num_steps"]:
        edits["time.num_steps"] = spec["num_steps"]
    if config["law"] != scene.get("contact", {}).get("law", "unilateral"):
        edits["contact.law"] = config["law"]
    shape = scene["tool"]["shape"]
    if "mesh" in shape:
        edits["tool.shape.mesh.file"] = absolute(shape["mesh"]["file"])
    if "body" in scene:
        body = variant_body(scene["body"], config["mesh"], youngs_scale)
        for key in ("mesh", "visual", "collision", "element") + (("material",) if youngs_scale != 1.0
                                                                  else ()):
            if key in body:
                edits[f"body.{key}"] = body[key]
        edits["body.elasticity"] = config["elasticity"]
    if "objects" in scene:
        objects = copy.deepcopy(scene["objects"])
        first = True
        for item in objects:
            if "rigid" in item and "mesh" in item["rigid"]["shape"]:
                item["rigid"]["shape"]["mesh"]["file"] = absolute(item["rigid"]["shape"]["mesh"]
                                                                  ["file"])
            if "deformable" in item:
                item["deformable"] = variant_body(item["deformable"], config["mesh"],
                                                  youngs_scale)
                if first:
                    item["deformable"]["elasticity"] = config["elasticity"]
                first = False
        edits["objects"] = objects
    return edits


def describe(spec, config, changed_only=None):
    parts = {"mesh": mesh_label(spec, config["mesh"]) if spec["fem"] else "no FEM built",
             "elasticity": config.get("elasticity") if spec["fem"] else None,
             "compliance": config.get("compliance") if spec["fem"] else None,
             "law": config["law"], "visual_hz": rate_text(config["visual_hz"])}
    keys = changed_only if changed_only is not None else list(parts)
    return ", ".join(parts[k] for k in keys if parts.get(k))


def short_value(spec, knob, value):
    if knob == "mesh":
        return mesh_label(spec, value)
    if knob == "visual_hz":
        return rate_text(value)
    return str(value)


# ---------------------------------------------------------------------------- the runs

class SceneRuns:
    """Runs configurations of one scene once each (a repeated configuration is looked up)."""

    def __init__(self, bench, spec):
        self.bench, self.spec, self.cache, self.reference = bench, spec, {}, None

    def key(self, config):
        return tuple(config.get(k) for k in ("mesh", "elasticity", "compliance", "law",
                                             "visual_hz"))

    def run(self, config, knob, again=None):
        """One `hapsim sim` of the configuration (looked up unless run again: "repeat" as it is,
        "perturbed" with every Young's modulus times 1 + PERTURBATION) and its error against the
        first run made (the finest). The record names its folder under the bench's output."""
        key = self.key(config)
        if key in self.cache and again is None:
            return self.cache[key]
        spec = self.spec
        slug = "_".join(str(v) for v in key if v is not None).replace(".", "p")
        name = f"economy_{spec['name']}_{slug}" + (f"_{again}" if again else "")
        self.bench.progress(f"economy: {spec['name']}: {knob}: {describe(spec, config)}")
        options = ["--visual-hz", config["visual_hz"]]
        if spec["fem"]:
            options += ["--compliance", config["compliance"]]
        if spec["mode"] != spec["scene"].get("haptic", {}).get("mode", DEFAULT_MODE):
            options += ["--mode", spec["mode"]]
        started = time.monotonic()
        record = {"config": dict(config), "description": describe(spec, config)}
        youngs_scale = 1.0 + PERTURBATION if again == "perturbed" else 1.0
        if youngs_scale != 1.0:
            record["youngs_scale"] = youngs_scale
        try:
            scene = self.bench.scene_variant(spec["path"], edits_for(spec, config, youngs_scale),
                                             name)
            summary, frames, folder = self.bench.sim(scene, name, *options)
        except BenchError as error:
            record["failed"] = str(error).splitlines()[-1][:300]
            if again is None:
                self.cache.setdefault(key, record)
            return record
        _, force = read_forces(folder)
        frame_ms = summary["frame_stage_median_ms"]["total"]
        record.update({
            "folder": os.path.relpath(folder, self.bench.out_dir),
            "frame_ms": frame_ms, "cost_ms_per_s": frame_ms * config["visual_hz"],
            "mean_cost_ms_per_s": sum(r["total_ms"] for r in frames) / spec["duration_s"],
            "max_contacts": summary["max_contacts"], "peak_force_N": summary["peak_force_N"],
            "wall_s": time.monotonic() - started})
        if self.reference is None:
            self.reference = force
        e = errors(force, self.reference)
        if not all(math.isfinite(v) for v in e.values()):
            record["failed"] = "non-finite device force"
        else:
            record.update({"rms_error_N": e["rms_N"], "max_error_N": e["max_N"]})
        if again is None:
            self.cache.setdefault(key, record)
        return record


def within(record, tolerance_N):
    return "failed" not in record and record["rms_error_N"] <= tolerance_N


def sweep_knobs(runs, spec, tolerance_N):
    """Each knob alone moved from the finest over its values; its cheapest value within the
    tolerance (the finest value is always there: the finest run against itself, error 0)."""
    sweeps, chosen = {}, {}
    for knob in spec["knobs"]:
        sweep = []
        for value in spec["values"][knob]:
            config = dict(spec["finest"], **{knob: value})
            sweep.append(dict(runs.run(config, knob), knob=knob, value=value,
                              label=short_value(spec, knob, value)))
        sweeps[knob] = sweep
        ok = [r for r in sweep if within(r, tolerance_N)]
        chosen[knob] = min(ok, key=lambda r: r["cost_ms_per_s"])["value"]
    return sweeps, chosen


def combine(runs, spec, sweeps, chosen, tolerance_N):
    """The knobs' choices run together. While that is off the tolerance, the moved knob whose own
    step cost the most error goes back to its next value towards the finest that was within the
    tolerance alone. Returns (configuration, its run, back-offs, every combined run)."""
    config = dict(spec["finest"], **chosen)
    backoffs, attempts = [], [runs.run(config, "combined")]
    while not within(attempts[-1], tolerance_N) and len(backoffs) < MAX_BACKOFFS:
        moved = [k for k in spec["knobs"] if config[k] != spec["finest"][k]]
        if not moved:
            break
        own = {k: next(r for r in sweeps[k] if r["value"] == config[k]) for k in moved}
        knob = max(moved, key=lambda k: own[k]["rms_error_N"])
        values = spec["values"][knob]
        back = next(r["value"] for r in sweeps[knob][values.index(config[knob]) + 1:]
                    if within(r, tolerance_N))
        backoffs.append({"knob": knob, "from": short_value(spec, knob, config[knob]),
                         "to": short_value(spec, knob, back),
                         "error_before_N": attempts[-1].get("rms_error_N")})
        config = dict(config, **{knob: back})
        attempts.append(runs.run(config, "combined (backed off)"))
    if within(attempts[-1], tolerance_N):
        return config, attempts[-1], backoffs, attempts
    # No combination fits: the cheapest run seen that does (a single knob's, or the finest).
    seen = [r for sweep in sweeps.values() for r in sweep] + attempts
    best = min((r for r in seen if within(r, tolerance_N)), key=lambda r: r["cost_ms_per_s"])
    return dict(best["config"]), best, backoffs, attempts


def run_scene(bench, spec):
    started = time.monotonic()
    runs = SceneRuns(bench, spec)
    finest = runs.run(spec["finest"], "finest")
    if "failed" in finest:
        raise BenchError(f"economy: {spec['name']}: the finest configuration failed: "
                         f"{finest['failed']}")
    # The comparison assumes a configuration gives one force history: the finest, run again; and
    # that the history is well posed: the finest with its stiffness moved far below any knob's
    # effect (a contact that flips on rounding sends a chaotic scene's history elsewhere).
    repeat = runs.run(spec["finest"], "finest, again (determinism)", again="repeat")
    perturbed = (runs.run(spec["finest"], f"finest, E × (1 + {PERTURBATION:g})",
                          again="perturbed") if spec["fem"] else None)
    peak_N = max(math.sqrt(sum(c * c for c in f)) for f in runs.reference)
    tolerance_N = max(TOLERANCE_FRACTION * peak_N, TOLERANCE_FLOOR_N)
    sweeps, chosen = sweep_knobs(runs, spec, tolerance_N)
    config, verified, backoffs, attempts = combine(runs, spec, sweeps, chosen, tolerance_N)
    combined_fits = within(attempts[-1], tolerance_N)
    changed = [k for k in spec["knobs"] if config[k] != spec["finest"][k]]
    return {
        "scene": spec["path"], "fem_built": spec["fem"], "haptic_mode": spec["mode"],
        "duration_s": spec["duration_s"], "shortened": spec["plan"].get("why", ""),
        "knobs": spec["knobs"], "fixed_knobs": fixed_knobs(spec),
        "peak_force_N": peak_N, "tolerance_N": tolerance_N,
        "finest": dict(finest, description=describe(spec, spec["finest"])),
        "finest_repeat": repeat,
        "finest_perturbed": perturbed,
        "sweeps": sweeps,
        "combined_runs": [dict(r, label="combined" if i == 0 else f"backed off {i}")
                          for i, r in enumerate(attempts)],
        "chosen": {"config": dict(config), "description": describe(spec, config),
                   "changed": describe(spec, config, changed) if changed else "nothing",
                   "folder": verified["folder"],
                   "rms_error_N": verified["rms_error_N"], "max_error_N": verified["max_error_N"],
                   "cost_ms_per_s": verified["cost_ms_per_s"],
                   "mean_cost_ms_per_s": verified["mean_cost_ms_per_s"],
                   "within_tolerance": combined_fits, "backoffs": backoffs,
                   "saving": finest["cost_ms_per_s"] / verified["cost_ms_per_s"],
                   "mean_saving": finest["mean_cost_ms_per_s"] / verified["mean_cost_ms_per_s"]},
        "wall_s": time.monotonic() - started}


def fixed_knobs(spec):
    """Why a knob is not swept in this scene."""
    why = {}
    if not spec["fem"]:
        why.update({"mesh": "no FEM built", "elasticity": "no FEM built",
                    "compliance": "no FEM built"})
    elif spec["mesh_kind"] == "file":
        why["mesh"] = "file mesh, as shipped"
    if len(spec["values"]["law"]) == 1:
        why["law"] = ("rigid objects take only unilateral or friction, and the scene has no "
                      "friction" if has_rigid_objects(spec["scene"]) else "the scene's own only")
    for knob in KNOBS:
        if knob not in spec["knobs"] and knob not in why:
            why[knob] = "not in the quick run"
    return why


def run(bench):
    specs, skipped = select_scenes(bench.quick)
    scenes = {}
    for name, spec in specs.items():
        bench.progress(f"economy: {name} ({', '.join(spec['knobs'])})")
        scenes[name] = run_scene(bench, spec)
    output = {"tolerance": {"fraction_of_peak": TOLERANCE_FRACTION, "floor_N": TOLERANCE_FLOOR_N},
              "scenes": scenes, "skipped": skipped,
              "figures": [chart(bench, scenes)], "markdown": []}
    output["markdown"] = markdown(scenes, skipped, output["tolerance"])
    return output
