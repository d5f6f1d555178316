"""The cantilever's part of RESULTS.md (cantilever.py): the references, the error per lattice and
elasticity, the Richardson limits, the lattice orientations' differences and the settling, as
Markdown lines; with the two helpers the experiment's charts and run share with it (which runs are
the base lattice, a lattice's label).
"""
import math

from beam_theory import E_PA, NU


def is_base(r):
    """The scene's orientation on an n × n/10 × n/10 lattice (cubic cells), linear tets."""
    return (r["orientation"] == "x" and r["m"] * 10 == r["n"] and r.get("element", "p1") == "p1"
            and r.get("cell_size_m") is None)


def quadratic_markdown(runs):
    """The quadratic element's runs and the unstructured meshes' (corotational, beam along x), each
    beside the corotational linear lattices' error at the same mean step cost (log-interpolated
    along them)."""
    quadratic = [r for r in runs if r.get("element") == "p2" or r.get("cell_size_m")]
    if not quadratic:
        return []
    md = ["Quadratic tets (`element: p2`, corotational, beam along x; issue 27) against the "
          "linear ones at the same mean step, on lattices and on unstructured tets (Gmsh, from "
          "the beam's closed surface scenes/meshes/beam.obj at the cell size given):", "",
          "| load | mesh | element | tets | nodes | mean / median step (ms) | vertical error | error | "
          "P1 corotational lattices at that cost |", "|---|---|---|---:|---:|---:|---:|---:|---:|"]
    for r in quadratic:
        linear = sorted((p for p in runs if is_base(p) and p["load"] == r["load"]
                         and p["elasticity"] == "corotational"), key=lambda p: p["mean_ms"])
        at_cost = "outside the linear lattices' costs"
        for a, b in zip(linear, linear[1:]):
            if a["mean_ms"] <= r["mean_ms"] <= b["mean_ms"]:
                t = math.log(r["mean_ms"] / a["mean_ms"]) / math.log(b["mean_ms"] / a["mean_ms"])
                error = a["relative_error"] + t * (b["relative_error"] - a["relative_error"])
                at_cost = (f"{100 * error:.1f} % (ratio {r['relative_error'] / error:.2f})"
                           if error else "0")
        md.append(f"| {r['load']} | {mesh_label(r)} | {r['element'].upper()} | {r['tets']} | "
                  f"{r['nodes']} | "
                  f"{r['mean_ms']:.2f} / {r['median_ms']:.2f} | {100 * r['vertical_error']:+.1f} % "
                  f"| {100 * r['relative_error']:.1f} % | {at_cost} |")
    return md + [""]


def mesh_label(r):
    if r.get("cell_size_m"):
        return f"unstructured, {1e3 * r['cell_size_m']:g} mm"
    return "×".join(str(c) for c in r["cells"])


def markdown(runs, refs, extrapolated, wall_s):
    small, large = refs["small"], refs["large"]
    md = [f"`hapsim fem` on scenes/cantilever.yaml (0.5 m, 5 × 5 cm, E {E_PA:g} Pa, ν {NU}, "
          "clamped face, self-weight), settled static tip on the neutral axis. Small load (g/10): "
          f"Euler–Bernoulli {1e3 * small['euler_bernoulli_m']:.3f} mm + Timoshenko shear (κ 5/6) "
          f"{1e3 * small['timoshenko_shear_m']:.3f} mm. Large load (5 g): the elastica under its "
          f"own weight, with the same shear term: tip ({1e3 * large['tip_m'][0]:.2f}, "
          f"{1e3 * large['tip_m'][1]:.2f}) mm axial, vertical (plain inextensible elastica "
          f"({1e3 * large['elastica_m'][0]:.2f}, {1e3 * large['elastica_m'][1]:.2f}) mm; linear "
          f"theory would say {1e3 * (large['euler_bernoulli_m'] + large['timoshenko_shear_m']):.1f}"
          " mm down and no shortening). Error: small load |vertical − δ|/δ, large load "
          "|u − u_ref|/|u_ref| over axial and vertical; signed errors below (negative: too stiff "
          "or too little shortening).", ""]
    base = [r for r in runs if is_base(r)]
    finest = max(r["n"] for r in base)
    coarsest = min(r["n"] for r in base)

    def pick(load, elasticity, n):
        return next(r for r in base
                    if (r["load"], r["elasticity"], r["n"]) == (load, elasticity, n))

    co, li = pick("large", "corotational", finest), pick("large", "linear", finest)
    coarse = pick("small", "linear", coarsest)
    linear_theory = ((large["euler_bernoulli_m"] + large["timoshenko_shear_m"])
                     / -large["tip_m"][1])
    floor = abs(large["tip_m"][0]) / math.hypot(*large["tip_m"])
    md += [f"On the finest lattice ({mesh_label(co)}) the corotational tip is "
           f"{100 * co['relative_error']:.1f} % from the elastica (vertical "
           f"{100 * co['vertical_error']:+.1f} %, axial shortening "
           f"{100 * co['axial_error']:+.0f} %). Linear elasticity cannot shorten the beam (axial "
           "−100 %) and its vertical tip converges to linear theory's, "
           f"{100 * (linear_theory - 1):+.1f} % past the elastica "
           f"({100 * li['vertical_error']:+.1f} % on that lattice): its error "
           f"({100 * li['relative_error']:.1f} % there) cannot fall below {100 * floor:.1f} %, the "
           "shortening's share of the tip's displacement. "
           f"The coarsest lattice ({mesh_label(coarse)}) is "
           f"{-100 * coarse['vertical_error']:.0f} % too stiff at the small load: linear tets lock "
           "in bending, and converge with refinement.", ""]
    md += ["| load | lattice | tets | elasticity | mean / median step (ms) | tip axial, vertical "
           "(mm) | vertical error | axial error | error |",
           "|---|---|---:|---|---:|---:|---:|---:|---:|"]
    for r in runs:
        if not is_base(r):
            continue
        md.append(f"| {r['load']} | {mesh_label(r)} | {r['tets']} | {r['elasticity']} | "
                  f"{r['mean_ms']:.2f} / {r['median_ms']:.2f} | {1e3 * r['tip_axial_m']:.2f}, "
                  f"{-1e3 * r['tip_along_load_m']:.2f} | {100 * r['vertical_error']:+.1f} % | "
                  + (f"{100 * r['axial_error']:+.0f} % | " if r["load"] == "large" else "– | ")
                  + f"{100 * r['relative_error']:.1f} % |")
    md.append("")
    if extrapolated:
        md.append("Richardson extrapolation of the vertical tip over the three finest lattices "
                  "(where the FEM converges, against the reference): " + "; ".join(
                      f"{load} {elasticity}: order {e['order']:.2f}, limit "
                      f"{100 * (e['limit_along_load_m'] / refs[load]['tip_m'][1] * -1 - 1):+.1f} %"
                      for (load, elasticity), e in extrapolated.items())
                  + ". Timoshenko's shear term is "
                  f"{100 * small['timoshenko_shear_m'] / -small['tip_m'][1]:.1f} % of the "
                  "reference, and how much of it a beam clamped over its whole face (Poisson "
                  "contraction and warping held at the root) shows, beam theory does not say: "
                  "limits within about that are within the reference's own uncertainty.")
        md.append("")
    md.append("Lattice orientation: difference of the tip, |Δu| / |u|, from the beam along x on "
              "the same lattice, load and elasticity. y, z and diag are images of the beam along x "
              "under symmetries of the lattice (its five-tet cut is invariant under permutations "
              "and, with even cell counts, reflections of the axes; a square section bends alike "
              "about every axis, so for linear elasticity the diagonal load is the superposition "
              "of two mirror images): linear runs differ by the solver's tolerance. "
              "Corotational elasticity has no superposition, so its diagonal load's difference is "
              "the lattice's anisotropy under large rotations. The one other "
              "mesh difference an axis-aligned beam can see is the cut's phase at the clamp: "
              "with an odd number of cells along the beam, the beam along −x (reversed) starts "
              "with the other cut than the beam along +x on the same lattice.")
    md.append("")
    md.append("| load | elasticity | lattice | y | z | diag | reversed, on (n+1) × m × m |")
    md.append("|---|---|---|---:|---:|---:|---:|")

    def find(load, elasticity, n, m, orientation):
        for o in runs:
            if (o["load"], o["elasticity"], o["n"], o["m"], o["orientation"]) == (
                    load, elasticity, n, m, orientation) and o.get("element", "p1") == "p1":
                return o
        return None

    def diff(o, r):
        if o is None or r is None:
            return "–"
        a = (o["tip_axial_m"], o["tip_along_load_m"], o["tip_lateral_m"])
        b = (r["tip_axial_m"], r["tip_along_load_m"], r["tip_lateral_m"])
        return f"{100 * math.dist(a, b) / math.hypot(b[0], b[1]):.2g} %"

    for r in runs:
        if not is_base(r):
            continue
        key = (r["load"], r["elasticity"], r["n"], r["m"])
        others = [find(*key, o) for o in ("y", "z", "diag")]
        reversed_ = (find(*key[:2], r["n"] + 1, r["m"], "reversed"),
                     find(*key[:2], r["n"] + 1, r["m"], "x"))
        if not any(others) and reversed_[0] is None:
            continue
        md.append(f"| {r['load']} | {r['elasticity']} | {mesh_label(r)} | "
                  + " | ".join(diff(o, r) for o in others) + f" | {diff(*reversed_)} |")
    md.append("")
    lateral = max(r["tip_lateral_m"] / math.hypot(r["tip_axial_m"], r["tip_along_load_m"])
                  for r in runs)
    md.append(f"Out of the load plane the tip moves at most {lateral:.1e} of its displacement "
              "(any orientation).")
    md.append("")
    worst = max(runs, key=lambda r: r["settling"])
    md.append(f"Settling: over the last 10 % of the steps the tip stays within "
              f"{worst['settling']:.1e} of its final displacement (worst run: {worst['load']} "
              f"{worst['orientation']} {mesh_label(worst)} {worst['elasticity']}); "
              f"{len(runs)} runs, {wall_s:.0f} s.")
    md.append("")
    return md
