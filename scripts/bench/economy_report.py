"""The economy experiment's part of RESULTS.md (economy.py): per scene, the chart of each knob's
sweep (error against the finest configuration over the visual compute per simulated second) with
the chosen configuration ringed, and the tables of the choices and the sweeps.
"""
from common import place_labels, plt, rate_text, save_figure

KNOB_NAMES = {"mesh": "mesh", "elasticity": "element law", "compliance": "compliance",
              "law": "contact law", "visual_hz": "visual rate", "combined": "combined"}
COLORS = {"mesh": "C0", "elasticity": "C1", "compliance": "C2", "law": "C4", "visual_hz": "C3",
          "combined": "k"}

def chart(bench, scenes):
    names = list(scenes)
    cols = min(4, len(names) + 1)  # one panel more, for the legend the scenes share
    rows = (len(names) + cols) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4.6 * cols, 4.2 * rows), squeeze=False)
    for axis in axes.flat[len(names):]:
        axis.axis("off")
    legend = {}  # label → handle, over every scene's panel
    placements = []  # (axis, labels): placed once every panel is set, as the layout then holds
    for axis, name in zip(axes.flat, names):
        result = scenes[name]
        points = [r for sweep in result["sweeps"].values() for r in sweep
                  if "failed" not in r and r["config"] != result["finest"]["config"]]
        extra = [dict(r, knob="combined") for r in result["combined_runs"]
                 if "failed" not in r and r["config"] != result["finest"]["config"]]
        tolerance = result["tolerance_N"]
        positive = [r["rms_error_N"] for r in points + extra if r["rms_error_N"] > 0]
        # The panel spans at most 10⁻³ to 10² times the tolerance: a run outside (a zero or
        # round-off error, a rate that blows up) sits on that edge as a triangle pointing off the
        # scale, its label saying its error, so the others keep their room.
        floor = max(min(positive + [tolerance]) / 3.0, tolerance / 1e3)
        ceiling = max(min(max(positive + [tolerance]), 1e2 * tolerance), floor)

        def shown(error):
            return min(max(error, floor), ceiling)

        def label_text(r, text):
            error = r["rms_error_N"]
            return text if floor <= error <= ceiling else f"{text} ({error:.2g} N)"

        labels = {}  # knob → its points' labels, placed once the axes are set
        for knob in result["knobs"] + ["combined"]:
            mine = [r for r in points + extra if r["knob"] == knob]
            if not mine:
                continue
            named = False  # the knob's legend entry: its first part drawn, whichever it is
            for part, marker in ((lambda e: floor <= e <= ceiling,
                                  "s" if knob == "combined" else "o"),
                                 (lambda e: e < floor, "v"), (lambda e: e > ceiling, "^")):
                these = [r for r in mine if part(r["rms_error_N"])]
                if these:
                    axis.scatter([r["cost_ms_per_s"] for r in these],
                                 [shown(r["rms_error_N"]) for r in these], color=COLORS[knob],
                                 marker=marker, s=22, zorder=3,
                                 label=None if named else KNOB_NAMES[knob])
                    named = True
            # Rates from the value: results.json files of earlier runs hold "33.3333 Hz".
            labels[knob] = [(r["cost_ms_per_s"], shown(r["rms_error_N"]),
                             label_text(r, rate_text(r["value"]) if knob == "visual_hz"
                                        else r["label"]), COLORS[knob]) for r in mine]
        chosen = result["chosen"]
        axis.scatter([chosen["cost_ms_per_s"]], [shown(chosen["rms_error_N"])], s=180,
                     facecolors="none", edgecolors="r", lw=2, zorder=4, label="chosen")
        axis.axhline(tolerance, color="r", ls="--", lw=1)
        axis.axvline(result["finest"]["cost_ms_per_s"], color="k", ls=":", lw=1)
        axis.annotate("finest", (result["finest"]["cost_ms_per_s"], 0.03),
                      xycoords=("data", "axes fraction"), rotation=90, fontsize=7, ha="right")
        axis.set(xscale="log", yscale="log",
                 xlabel="visual compute per simulated second (ms/s)",
                 ylabel="device force RMS error vs finest (N)",
                 # The tolerance in the title, not beside its line: the runs crowd the line.
                 title=(f"{name}: chosen {chosen['saving']:.1f}× cheaper"
                        if chosen["config"] != result["finest"]["config"]
                        else f"{name}: the finest is needed") +
                 f"\n(dashed: tolerance {result['tolerance_N']:.3g} N"
                 + ("" if well_posed(result) is not False else
                    f"; E × ({perturbation_text(result['finest_perturbed'])}) moves it "
                    f"{result['finest_perturbed']['rms_error_N']:.2g} N") + ")")
        axis.title.set_fontsize(10)
        # A panel spanning less than a decade labels its minor ticks (3×10⁻², 4×10⁻², ...):
        # smaller figures keep them apart.
        axis.tick_params(which="both", labelsize=7)
        axis.grid(True, which="both", alpha=0.3)
        # The combined runs first: their labels say what the squares are.
        placements.append((axis, [label for knob in ["combined"] + result["knobs"]
                                  for label in labels.get(knob, [])],
                           [(chosen["cost_ms_per_s"], shown(chosen["rms_error_N"]), 8)]))
        for handle, label in zip(*axis.get_legend_handles_labels()):
            legend.setdefault(label, handle)
    axes.flat[len(names)].legend(list(legend.values()), list(legend.keys()), loc="center",
                                 fontsize=9, title="moved from the finest configuration")
    for axis, labels, ring in placements:
        place_labels(axis, labels, fontsize=6.5, avoid=ring)
    save_figure(fig, bench.path("economy.png"))
    return {"file": "economy.png",
            "caption": "Per scene, the device-force error against the finest configuration over "
                       "the visual compute per simulated second, one knob moved at a time "
                       "(colours; labels: the knob's value) and the knobs' choices combined "
                       "(squares); red ring: the chosen configuration, dashed: the tolerance, "
                       "dotted: the finest configuration's cost; a triangle: a run off the scale "
                       "(below 10⁻³ or above 10² times the tolerance, or an exact zero), at its "
                       "edge, its label giving its error."}


def well_posed(result):
    """Whether the finest run's force moved by no more than the tolerance when its Young's moduli
    were perturbed (economy.PERTURBATION): True, False, or None where that run is missing (no FEM)
    or failed."""
    perturbed = result.get("finest_perturbed")
    if not perturbed or "rms_error_N" not in perturbed:
        return None
    return perturbed["rms_error_N"] <= result["tolerance_N"]


def perturbation_text(perturbed):
    """'1 + 1e-12', from the perturbed run's own record."""
    return f"1 + {perturbed['youngs_scale'] - 1.0:.0e}"


def sensitivity_text(scenes):
    """The finest runs' RMS difference with every Young's modulus slightly larger
    (economy.PERTURBATION), and the scenes where it passes the tolerance."""
    perturbed = {name: r["finest_perturbed"] for name, r in scenes.items()
                 if r.get("finest_perturbed")}
    if not perturbed:
        return ""
    scale = perturbation_text(next(iter(perturbed.values())))
    text = (f"Run once more with every Young's modulus {scale} times as large, a change far "
            "below any knob's, the finest configuration's force moved by (RMS) "
            + ", ".join(f"{name} {r['rms_error_N']:.2g} N" if "rms_error_N" in r
                        else f"{name}: failed ({r.get('failed', 'no result')})"
                        for name, r in perturbed.items()) + ".")
    unstable = [name for name in perturbed if well_posed(scenes[name]) is False]
    if unstable:
        text += (" In " + ", ".join(unstable) + " that is more than the tolerance: the scene's "
                 "force history is not well posed (a contact that flips on rounding sends it "
                 "elsewhere), and its knobs' errors below do not rank its configurations.")
    return text


def markdown(scenes, skipped, tolerance):
    sensitivity = sensitivity_text(scenes)
    md = ["Per scene, one knob at a time moved from the finest configuration (refined mesh of "
          "quadratic tets, corotational, exact compliance, the scene's contact law, 100 Hz visual "
          "frames), "
          "each knob set to its cheapest value whose device-force RMS error against the finest "
          f"run stays within the tolerance, max({100 * tolerance['fraction_of_peak']:g} % of the finest run's "
          f"peak device force, {tolerance['floor_N']:g} N), then the knobs' choices run together and "
          "checked; cost is the visual process's compute per simulated second (median frame × "
          "visual rate; the saving by the mean frame in brackets). The finest configuration is run "
          "twice: the repeat's RMS difference (a configuration gives one force history, so the "
          "errors below are the knobs' own) was "
          + ", ".join(f"{name} {r['finest_repeat'].get('rms_error_N', float('nan')):.2g} N"
                      for name, r in scenes.items()) + "."
          + (" " + sensitivity if sensitivity else ""), "",
          "The mesh knob moves the element order with the size (issue 27): linear tets (P1) at "
          "0.5, 0.75 and 1 times the shipped cells and at the finest linear cells, quadratic ones "
          "(P2) at 0.5 times the shipped cells and at half the finest linear cells, the finest "
          "mesh of all: about the nodes of the finest linear one, and at equal cost 3-10 times "
          "closer to the closed forms in the indentation and cantilever tables above, where "
          "linear tets lock at tissue-like Poisson ratios.", "",
          "| scene | finest (cost) | cheapest configuration | error RMS / max (N) | cost | "
          "saving |", "|---|---|---|---:|---:|---:|"]
    for name, r in scenes.items():
        c = r["chosen"]
        backed = "".join(f"; backed off {b['knob']} {b['from']} → {b['to']}"
                         for b in c["backoffs"])
        kept = ("" if c["within_tolerance"] else
                " (the combination is off the tolerance: the cheapest single run within it)")
        md.append(f"| {name} | {r['finest']['description']} ({r['finest']['cost_ms_per_s']:.3g} "
                  f"ms/s) | {c['description']}{backed}{kept} | {c['rms_error_N']:.3f} / "
                  f"{c['max_error_N']:.3f} (tol. {r['tolerance_N']:.3f}) | "
                  f"{c['cost_ms_per_s']:.3g} ms/s | {c['saving']:.1f}× ({c['mean_saving']:.1f}×) |")
    md += ["", "Each knob's sweep from the finest configuration: value, RMS error (N), cost "
           "(ms/s); ✓ within the tolerance, **bold** the value taken:", "",
           "| scene | knob | sweep |", "|---|---|---|"]
    for name, r in scenes.items():
        for knob, sweep in r["sweeps"].items():
            cells = []
            for s in sweep:
                if "failed" in s:
                    cells.append(f"{s['label']}: failed")
                    continue
                text = (f"{s['label']}: {s['rms_error_N']:.3f}, {s['cost_ms_per_s']:.3g}"
                        + (" ✓" if s["rms_error_N"] <= r["tolerance_N"] else ""))
                taken = r["chosen"]["config"][knob] == s["value"]
                cells.append(f"**{text}**" if taken else text)
            md.append(f"| {name} | {KNOB_NAMES[knob]} | " + "; ".join(cells) + " |")
        fixed = r["fixed_knobs"]
        if not r["fem_built"]:
            md.append(f"| {name} | mesh, element law, compliance | not swept: no FEM built |")
        for knob, why in fixed.items():
            if not r["fem_built"] and knob in ("mesh", "elasticity", "compliance"):
                continue
            md.append(f"| {name} | {KNOB_NAMES[knob]} | not swept: {why} |")
    md.append("")
    notes = [f"{name}: {r['shortened']}" for name, r in scenes.items() if r["shortened"]]
    if notes:
        md += ["Scripts shortened (time.num_steps) to fit the bench: " + "; ".join(notes) + ".",
               ""]
    md += ["Skipped: " + "; ".join(f"{name} ({why})" for name, why in skipped.items()) + ".", ""]
    return md
