"""Stability maps: where each method fails (issue 12, item 3).

Six maps, each a sweep of `hapsim` runs with a stated criterion and the failing region shaded; each
map's module states its runs, its criterion and why:

1. explicit against implicit integration (`hapsim fem`, scenes/block_tiny.yaml undamped): the
   largest stable explicit step, bisected on dt per Young's modulus, against the theoretical
   2/ω_max; implicit Euler at 100 times that step (stability_explicit.py).
2. coupling stiffness against visual rate (`--mode coupling --device hand` on
   scenes/block_press.yaml, and the paper's `--mode linear` on the same grid);
3. penalty stiffness against the haptic update rate (`--mode penalty --device hand`).
   Both closed loops with the simulated hand are unstable where the device force oscillates by
   more than 0.1 N about its 50 ms mean (stability_loops.py).
4. equality against unilateral release: the straight press and lift of block_press with a sharp
   rim, scripted device, each cell at eight phases of the lift against the frame clock (quick:
   two); it sticks if, at its worst phase, the device is pulled more than 0.05 N beyond the
   reference's pull while the tool lifts off;
5. a stiff body under a fast tool: block_press with E 5e4–5e7 Pa, the device pressed 5 mm in
   0.8–0.01 s; it fails where the haptic tool penetrates more than 1 mm beyond the body's own give
   (both: stability_contact.py).
6. maps 1–5 again on a quadratic body (`body.element: p2`), compared cell by cell with the
   linear body's: a new unstable cell is one where only the quadratic body fails
   (stability_quadratic.py).

The scenes, colours and helpers the maps share are in stability_common.py.
"""
from stability_contact import fast_map, fast_markdown, release_map, release_markdown
from stability_explicit import explicit_map, explicit_markdown
from stability_loops import coupling_map, coupling_markdown, penalty_map, penalty_markdown
from stability_quadratic import quadratic_map, quadratic_markdown


def run(bench):
    output = {"figures": [], "markdown": []}
    for name, build, markdown in (("explicit", explicit_map, explicit_markdown),
                                  ("coupling", coupling_map, coupling_markdown),
                                  ("penalty", penalty_map, penalty_markdown),
                                  ("release", release_map, release_markdown),
                                  ("fast_tool", fast_map, fast_markdown)):
        result, figure = build(bench)
        output[name] = result
        output["figures"].append(figure)
        output["markdown"] += markdown(result)
    result, figure = quadratic_map(bench, output)
    output["quadratic"] = result
    output["figures"].append(figure)
    output["markdown"] += quadratic_markdown(result)
    return output
