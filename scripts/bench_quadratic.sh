#!/usr/bin/env bash
# Linear against quadratic tets (issue 27; docs/SCENES.md, "Quadratic tets"), the two tables there:
#  - the cantilever (scenes/cantilever.yaml at a tenth of its gravity, `hapsim fem`) on 10x1x1,
#    20x2x2 and 40x4x4 cells with `element: p1` and `p2`: the tip's vertical deflection against
#    beam theory (scripts/bench/beam_theory.py, Euler-Bernoulli + Timoshenko shear) and the step;
#  - Hertz (scenes/hertz_indentation.yaml, `hapsim sim`) on the 2m x 2m x m lattice graded 10:1:
#    the fitted coefficient's error (scripts/bench/indentation.py's fit) and the median frame, at
#    nu 0.45 and 0.49.
# Prints two Markdown tables. Run on an idle machine: the times are medians of one run each.
#
#   scripts/bench_quadratic.sh [OUT]   (default out/bench_quadratic; ~2 min)
set -euo pipefail
cd "$(dirname "$0")/.."
hapsim=build/apps/hapsim
[ -x "$hapsim" ] || scripts/setup.sh
out=${1:-out/bench_quadratic}
mkdir -p "$out"
/usr/bin/python3 - "$PWD" "$hapsim" "$out" <<'PY'
import json, os, subprocess, sys
repo, hapsim, out = sys.argv[1], os.path.abspath(sys.argv[2]), os.path.abspath(sys.argv[3])
sys.path.insert(0, os.path.join(repo, "scripts", "bench"))
import beam_theory, common, indentation  # noqa: E402

def variant(base, name, replacements, element):
    text = open(os.path.join(repo, base)).read()
    for old, new in replacements:
        if old not in text:
            sys.exit(f"bench_quadratic: '{old}' is not in {base}")
        text = text.replace(old, new)
    text = text.replace("  mesh:\n", f"  element: {element}\n  mesh:\n", 1)
    path = os.path.join(out, name + ".yaml")
    open(path, "w").write(text)
    return path

def progress(what):
    print(f"bench_quadratic: {what}", file=sys.stderr, flush=True)

reference_m = -beam_theory.references()["small"]["tip_m"][1]
print(f"Cantilever, a tenth of its weight, tip deflection against beam theory ({1e3 * reference_m:.3f} mm):\n")
print("| cells | P1: tets, nodes, error, step | P2: tets, nodes, error, step |\n|---|---|---|")
for cells in ("10, 1, 1", "20, 2, 2", "40, 4, 4"):
    row = []
    for element in ("p1", "p2"):
        name = f"cantilever_{element}_{cells.replace(', ', 'x')}"
        scene = variant("scenes/cantilever.yaml", name,
                        [("gravity_m_s2: [0, 0, -9.81]", "gravity_m_s2: [0, 0, -0.981]"),
                         ("cells: [40, 4, 4]", f"cells: [{cells}]")], element)
        progress(name)
        subprocess.run([hapsim, "fem", scene, "--out", os.path.join(out, name)], check=True,
                       cwd=repo, stdout=subprocess.DEVNULL)
        summary = json.load(open(os.path.join(out, name, "summary.json")))
        tip = -summary["probes"][0]["final_displacement_m"][2]
        row.append(f"{summary['num_tets']:,}, {summary['num_nodes']:,}, "
                   f"{100 * (tip / reference_m - 1):+.2f} %, {summary['timings']['total']['median_ms']:.3f} ms")
    print(f"| {cells.replace(', ', ' × ')} | {row[0]} | {row[1]} |")

print("\nHertz, fitted coefficient's error and median visual frame:\n")
print("| element, m | ν 0.45 | ν 0.49 |\n|---|---|---|")
bench = common.Bench(hapsim, out, False)
case = indentation.CASES["hertz"]
for element, cells in (("p1", 6), ("p1", 8), ("p2", 4), ("p2", 6)):
    row = []
    for nu in (0.45, 0.49):
        name = f"hertz_{element}_m{cells}_nu{nu:g}"
        scene = variant("scenes/hertz_indentation.yaml", name,
                        [("cells: [20, 20, 10]", f"cells: [{2 * cells}, {2 * cells}, {cells}]"),
                         ("poisson_ratio: 0.45", f"poisson_ratio: {nu}")], element)
        progress(name)
        summary, frames, _ = bench.sim(scene, name)
        coefficient, _ = indentation.fit(frames, case)
        analytic = case["coefficient_over_E_star"] * indentation.E_PA / (1 - nu * nu)
        row.append(f"{100 * (coefficient / analytic - 1):+.1f} %, "
                   f"{summary['frame_stage_median_ms']['total']:.2f} ms")
    print(f"| {element.upper()}, m {cells} ({20 * cells ** 3:,} tets) | {row[0]} | {row[1]} |")
PY
