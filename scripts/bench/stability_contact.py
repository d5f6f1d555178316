"""Stability maps 4 and 5: contact that releases and contact a fast tool can miss (issue 12, item 3;
see stability.py).

4. Equality against unilateral release: the straight press (5 mm) and lift of block_press with a
   sharp rim (the scene's rounded rim makes the equality law blow up during the press, recorded
   once), scripted device. The sticking force is the most negative device force z while lifting
   plus the tool's weight (the pull beyond gravity). A model frozen at a frame pulls from the
   moment its contacts turn to tension until the next frame, anything from nothing to a whole
   frame, so each cell is run with the script shifted by k/N of its visual frame (k = 0 … N−1)
   and judged on its worst phase. Criterion: it sticks if that is more than 0.05 N below the
   1 kHz reference's (the tool's own coupling ringing at separation; quick: the lcp mode's,
   which matches the reference).
5. A stiff body under a fast tool: block_press with E 5e4–5e7 Pa, the device pressed 5 mm in
   T = 0.8–0.01 s (scripted: a hand could not move that fast), the linear mode over E × speed and
   the other modes at 5 MPa. The haptic tool's penetration is its depth below the undeformed top
   minus the visual tool's (the body's own give). Criterion: it fails above 1 mm, and tunnels if it
   is that deep while its contact model holds no contact.
"""
import math

import numpy as np
from matplotlib.patches import Patch

from common import median, plt, save_figure
from stability_common import (FAIL_COLOR, PRESS, STABLE_COLOR, cell_map, finite, haptic,
                              press_scene)

STICK_MARGIN_N = 0.05
LIFT_S = 1.2  # the release script's lift starts here (unshifted)
# Phases per release cell. Hand runs on P1, unilateral law, linear mode, 25 Hz (2026-11-29): over
# eight phases the pull ran from −0.10 to −0.55 N, and the one phase the map used to run gave
# −0.14 N; the lcp mode's stayed at −0.090 N in every phase.
RELEASE_PHASES = 8
QUICK_RELEASE_PHASES = 2
PENETRATION_LIMIT_M = 0.001


# 4. equality against unilateral release --------------------------------------------------------

def release_scene(bench, law, rounded=False, edits=None, tag="", shift_s=0.0):
    """block_press pressed 5 mm straight down and lifted 4 mm above the start (no slide), the
    script after its first point shifted by shift_s."""
    base = press_scene()
    z0 = base["tool"]["position_m"][2]
    points = [(0.2, z0), (1.0, z0 - 0.005), (1.2, z0 - 0.005), (2.0, z0 + 0.004),
              (2.1, z0 + 0.004)]
    script = [{"t_s": 0.0, "position_m": [0.0, 0.0, z0]}] + [
        {"t_s": t + shift_s, "position_m": [0.0, 0.0, z]} for t, z in points]
    # The scene's frames to 2.1 s + shift (at its own dt_s; `edits` leave the time step alone).
    steps = 70 + math.ceil(shift_s / base["time"]["dt_s"] - 1e-9)
    changes = {"contact.law": law, "device.trajectory": script, "time.num_steps": steps}
    if not rounded:
        cylinder = dict(base["tool"]["shape"]["cylinder"])
        cylinder.pop("edge_radius_m", None)
        changes["tool.shape"] = {"cylinder": cylinder}
    changes.update(edits or {})
    name = (f"stab_release_{law}" + ("_rounded" if rounded else "") + tag
            + (f"_shift{1e3 * shift_s:g}ms" if shift_s else ""))
    return bench.scene_variant(PRESS, changes, name)


def release_run(bench, law, mode, hz, rounded=False, edits=None, tag="", shift_s=0.0):
    """One release run, the script shifted by shift_s; `edits` and `tag` as fast_run's."""
    label = (f"stab_release_{law}_{mode}_{hz:g}hz" + ("_rounded" if rounded else "") + tag
             + (f"_shift{1e3 * shift_s:g}ms" if shift_s else ""))
    scene = release_scene(bench, law, rounded, edits, tag, shift_s)
    options = ["--mode", mode] + ([] if mode == "reference" else ["--visual-hz", hz])
    summary, frames, folder = bench.sim(scene, label, *options)
    h = haptic(folder)
    weight_N = press_scene()["tool"]["mass_kg"] * 9.81
    lifting = h["t_s"] >= LIFT_S + shift_s
    i = int(np.argmin(h["force_z_N"][lifting]))
    frame_lift = [r["contact_force_z_N"] for r in frames if r["t_s"] >= LIFT_S + shift_s]
    return {"law": law, "mode": mode, "visual_hz": hz, "rounded_rim": rounded,
            "shift_s": shift_s, "sticking_N": finite(h["force_z_N"][lifting][i] + weight_N),
            "at_s": finite(h["t_s"][lifting][i]),
            "min_frame_contact_force_z_N": finite(min(frame_lift)) if frame_lift else None,
            "peak_force_N": finite(summary["peak_force_N"]),
            "max_contacts": summary["max_contacts"]}


def release_cell(bench, law, mode, hz, phases, edits=None, tag=""):
    """One cell of map 4: `phases` runs, the script shifted by k/phases of a visual frame. The
    cell is its worst run (a run without a finite force is the worst), with every phase's
    sticking force beside it. (At 200 Hz the shifts are 0.625 ms apart, finer than the 1 ms
    haptic step: the scripted device moves between steps, so they still differ.)"""
    runs = [release_run(bench, law, mode, hz, edits=edits, tag=tag, shift_s=k / (phases * hz))
            for k in range(phases)]
    worst = min(runs, key=lambda r: -math.inf if r["sticking_N"] is None else r["sticking_N"])
    frame_forces = [r["min_frame_contact_force_z_N"] for r in runs
                    if r["min_frame_contact_force_z_N"] is not None]
    return {**worst, "phase_shifts_s": [r["shift_s"] for r in runs],
            "phase_sticking_N": [r["sticking_N"] for r in runs],
            "min_frame_contact_force_z_N": min(frame_forces) if frame_forces else None,
            "max_contacts": max(r["max_contacts"] for r in runs)}


def phase_range(point):
    """(best, worst) sticking force over a cell's phases, or None if a phase had no finite force."""
    forces = point.get("phase_sticking_N", [point["sticking_N"]])
    return None if None in forces else (max(forces), min(forces))


def release_grid(quick):
    """([(law, mode), ...], [visual Hz, ...], phases per cell): the cells of map 4. The default
    mode, hybrid, holds the frame's active rows as equalities as the linear model does."""
    if quick:
        return [("equality", "linear"), ("unilateral", "lcp")], [20.0], QUICK_RELEASE_PHASES
    return ([("equality", "linear"), ("unilateral", "linear"), ("unilateral", "hybrid"),
             ("unilateral", "lcp")], [10.0, 20.0, 25.0, 50.0, 100.0, 200.0], RELEASE_PHASES)


def release_points(bench, edits=None, tag=""):
    """Every cell of map 4, each marked `sticks` against the baseline: the 1 kHz reference run
    on the same body (quick: the lcp mode's median). Returns (points, reference, baseline N,
    the baseline's name)."""
    combos, rates, phases = release_grid(bench.quick)
    points = []
    for law, mode in combos:
        for hz in rates:
            bench.progress(f"stability: release{tag}, {law} law, {mode}, visual {hz:g} Hz, "
                           f"{phases} phases")
            points.append(release_cell(bench, law, mode, hz, phases, edits=edits, tag=tag))
    reference = None
    if not bench.quick:
        bench.progress(f"stability: release{tag}, reference (everything at 1 kHz; ~30 s)")
        reference = release_run(bench, "unilateral", "reference", 1000.0, edits=edits, tag=tag)
    if reference is not None:
        baseline, baseline_name = reference["sticking_N"], "the 1 kHz reference"
    else:
        baseline = median([p["sticking_N"] for p in points
                           if p["mode"] == "lcp" and p["sticking_N"] is not None])
        baseline_name = "the lcp mode (quick: no reference run)"
    # A run without a finite device force (None) fails the release as surely as one that sticks.
    for p in points:
        p["sticks"] = p["sticking_N"] is None or p["sticking_N"] < baseline - STICK_MARGIN_N
    return points, reference, baseline, baseline_name


# The release map's (law, mode) pairs: colour and marker, the same on the linear and quadratic
# bodies' charts.
RELEASE_STYLES = {("equality", "linear"): ("C3", "o"), ("unilateral", "linear"): ("C0", "s"),
                  ("unilateral", "hybrid"): ("C4", "D"), ("unilateral", "lcp"): ("C2", "^")}


def release_axis(axis, rates, low, ylabel, title):
    """A release chart's axes: the visual rates on a log axis, the sticking force from `low`."""
    axis.set(xscale="log", ylim=(low, 0.05), xlabel="visual rate (Hz)", ylabel=ylabel, title=title)
    axis.set_xticks(rates)
    axis.set_xticklabels([f"{r:g}" for r in rates])
    axis.minorticks_off()
    axis.grid(True, alpha=0.3)


def release_map(bench):
    combos, rates, phases = release_grid(bench.quick)
    points, reference, baseline, baseline_name = release_points(bench)
    rounded = None
    if not bench.quick:
        bench.progress("stability: release, equality law on the scene's rounded rim, 50 Hz")
        rounded = release_run(bench, "equality", "linear", 50.0, rounded=True)
    measured = [p for p in points if p["sticking_N"] is not None]
    fig, axis = plt.subplots(figsize=(8, 4.8))
    low = min([p["sticking_N"] for p in measured] + [baseline]) - 0.1
    axis.axhspan(low, baseline - STICK_MARGIN_N, color=FAIL_COLOR, alpha=0.45, lw=0,
                 label=f"sticks: pulls > {STICK_MARGIN_N:g} N beyond "
                       f"{baseline_name.split(' (')[0]}")
    axis.axhline(baseline, color="k", ls="--", lw=1, label=f"{baseline_name}: {baseline:+.3f} N")
    for n, (law, mode) in enumerate(combos):
        chosen = [p for p in measured if p["law"] == law and p["mode"] == mode]
        color, marker = RELEASE_STYLES[(law, mode)]
        axis.plot([p["visual_hz"] for p in chosen], [p["sticking_N"] for p in chosen],
                  marker=marker, color=color, label=f"{law} law, --mode {mode}")
        # The phases' range, each pair's bars a little apart on the log axis.
        nudge = 1.05 ** (n - (len(combos) - 1) / 2)
        for p in chosen:
            span = phase_range(p)
            if span is not None:
                axis.plot([p["visual_hz"] * nudge] * 2, span, color=color, lw=3, alpha=0.5,
                          solid_capstyle="butt")
    axis.plot([], [], color="0.5", lw=3, alpha=0.5,
              label=f"range over the {phases} phases of the frame clock")
    axis.axhline(0, color="0.5", lw=0.8)
    release_axis(axis, rates, low, "sticking force: min(F_z) + m_tool g while lifting (N)",
                 "Release (sharp-rim block_press): pull on the device beyond the tool's\n"
                 "weight, the worst phase of the lift against the frame clock")
    axis.legend(fontsize=7, loc="lower right")
    save_figure(fig, bench.path("stability_release.png"))
    figure = {"file": "stability_release.png",
              "caption": "Equality against unilateral release: the most negative device force z "
                         "beyond the tool's weight while the tool lifts off, against the visual "
                         f"rate, at the worst of {phases} phases of the lift against the frame "
                         "clock (bars: every phase's range), red below the reference's value by "
                         "more than 0.05 N."}
    return {"scene": PRESS + " (sharp rim, straight press 5 mm and lift, scripted device)",
            "criterion": f"sticking_N < baseline − {STICK_MARGIN_N} N", "baseline_N": baseline,
            "baseline": baseline_name, "reference": reference, "rounded_rim_equality": rounded,
            "phases": phases, "points": points}, figure


def sticking_text(value_N):
    return "no finite force" if value_N is None else f"{value_N:+.3f}"


def cell_text(point):
    """A release cell: its worst phase's sticking force, in bold where it sticks, and its best
    phase's in brackets."""
    worst = sticking_text(point["sticking_N"])
    span = phase_range(point)
    best = (f" ({span[0]:+.3f})" if span is not None
            and len(point.get("phase_sticking_N", ())) > 1 else "")
    return (f"**{worst}**" if point["sticks"] else worst) + best


def release_combos(points):
    """The (law, mode) pairs of `points`, in the order they first appear."""
    return list(dict.fromkeys((p["law"], p["mode"]) for p in points))


def release_table(points):
    """Markdown rows: the sticking force (N) per law and mode against the visual rate, the worst
    phase's (bold where it sticks) and the best's."""
    rates = sorted({p["visual_hz"] for p in points})
    combos = release_combos(points)
    md = ["| law, mode | " + " | ".join(f"{hz:g} Hz" for hz in rates) + " |",
          "|---|" + "---:|" * len(rates)]
    for law, mode in combos:
        row = {p["visual_hz"]: p for p in points if (p["law"], p["mode"]) == (law, mode)}
        md.append(f"| {law}, {mode} | " + " | ".join(
            cell_text(row[hz]) if hz in row else "" for hz in rates) + " |")
    return md


def release_markdown(result):
    points = result["points"]
    combos = release_combos(points)
    sticks = {c: [p["visual_hz"] for p in points if (p["law"], p["mode"]) == c and p["sticks"]]
              for c in combos}
    worst = {c: min((p for p in points if (p["law"], p["mode"]) == c),
                    key=lambda p: -math.inf if p["sticking_N"] is None else p["sticking_N"])
             for c in combos}
    frame_min = min(p["min_frame_contact_force_z_N"] for p in points
                    if p["min_frame_contact_force_z_N"] is not None)
    lcp = [x for p in points if p["mode"] == "lcp"
           for x in p.get("phase_sticking_N", [p["sticking_N"]]) if x is not None]
    lcp_off = max(abs(x - result["baseline_N"]) for x in lcp) if lcp else None
    spans = [(phase_range(p), p) for p in points if phase_range(p) is not None]
    widest = max(spans, key=lambda s: s[0][0] - s[0][1]) if spans else None
    # Whether hybrid pulls less than the linear mode (unilateral law) at every rate both ran.
    worst_at = {(p["mode"], p["visual_hz"]): p["sticking_N"] for p in points
                if p["law"] == "unilateral"}
    hybrid_below_linear = all(
        worst_at[("hybrid", hz)] is not None and worst_at[("linear", hz)] is not None
        and worst_at[("hybrid", hz)] >= worst_at[("linear", hz)]
        for mode, hz in worst_at if mode == "hybrid" and ("linear", hz) in worst_at)
    said = "; ".join(f"{law}/{mode}: " + (", ".join(f"{hz:g}" for hz in hz_list) + " Hz"
                                         if hz_list else "never")
                     for (law, mode), hz_list in sticks.items())
    md = [f"**Equality against unilateral release** ({result['scene']}; sticking force = most "
          f"negative device force z while lifting plus the tool's weight; sticks if more than "
          f"{STICK_MARGIN_N:g} N below {result['baseline']}, {result['baseline_N']:+.3f} N, which "
          f"is the coupled tool ringing as it separates). Sticks at: {said}. Strongest pull: "
          + "; ".join(f"{law}/{mode} {sticking_text(worst[(law, mode)]['sticking_N'])} N at "
                      f"{worst[(law, mode)]['visual_hz']:g} Hz" for law, mode in combos)
          + (f". The frames' own contact force never pulls (its minimum while lifting is "
             f"{frame_min:+.3f} N): the pull is the linear model's between frames"
             if frame_min >= 0 else f". The frames' own contact force pulls too, down to "
             f"{frame_min:+.3f} N") + ". Why: the model "
          "holds the frame's active contacts as equalities until the next frame, so while the "
          "tool lifts they pull, longer at a low visual rate"
          + ("; this happens with the unilateral law too, since the frame's active set is "
             "frozen" if sticks.get(("unilateral", "linear")) else "")
          + (". How long they pull depends on where in the frame the contact turns to tension, "
             f"so each cell is the worst of {result['phases']} runs with the script shifted by "
             f"k/{result['phases']} of a visual frame; the widest spread, "
             f"{widest[1]['law']}/{widest[1]['mode']} at {widest[1]['visual_hz']:g} Hz, runs "
             f"from {widest[0][0]:+.3f} to {widest[0][1]:+.3f} N"
             if widest is not None and result.get("phases", 1) > 1 else "")
          + (". The default mode, hybrid, holds the frame's active rows as equalities too, each "
             "pulling no harder than it pushed at the frame (docs/CONTACT.md), and below 100 Hz "
             "builds its model with the haptic step's body compliance: it pulls "
             + ("less than the linear mode, and " if hybrid_below_linear else "")
             + ("sticks at " + ", ".join(f"{hz:g}" for hz in sticks[("unilateral", "hybrid")])
                + " Hz" if sticks[("unilateral", "hybrid")] else "never sticks")
             if ("unilateral", "hybrid") in sticks else "")
          + ". The lcp mode re-solves the unilateral problem every 1 ms"
          + (f" and stays within {lcp_off:.3f} N of {result['baseline'].split(' (')[0]}."
             if lcp_off is not None and result["reference"] is not None else ".")]
    rounded = result.get("rounded_rim_equality")
    if rounded:
        md[-1] += (f" On the scene's own rounded rim the equality law fails outright, already in "
                   f"the press: peak device force {rounded['peak_force_N']:.3g} N, the frame's "
                   f"contact force down to {rounded['min_frame_contact_force_z_N']:.3g} N, "
                   f"{rounded['max_contacts']} contacts at {rounded['visual_hz']:g} Hz (the "
                   "rim's feature points; the sharp rim has at most "
                   f"{max(p['max_contacts'] for p in points if p['law'] == 'equality')}).")
    md += [""] + release_table(points)
    md += ["", "(N, the worst phase; bold: sticks; in brackets the best phase)", ""]
    return md


# 5. stiff body under a fast tool ---------------------------------------------------------------

def fast_run(bench, mode, E, press_s, depth_m=0.005, edits=None, tag=""):
    """block_press with E and a press of depth_m in press_s under `mode`; `edits` (dotted keys,
    as Bench.scene_variant) change the scene further, `tag` names such a variant's runs."""
    base = press_scene()
    z0 = base["tool"]["position_m"][2]
    top_plus_half = base["body"]["mesh"]["box"]["max_m"][2] + \
        base["tool"]["shape"]["cylinder"]["length_m"] / 2
    dt = base["time"]["dt_s"]
    end = 0.1 + press_s + 0.3
    script = [{"t_s": 0.0, "position_m": [0.0, 0.0, z0]},
              {"t_s": 0.1, "position_m": [0.0, 0.0, z0]},
              {"t_s": 0.1 + press_s, "position_m": [0.0, 0.0, z0 - depth_m]},
              {"t_s": end, "position_m": [0.0, 0.0, z0 - depth_m]}]
    label = f"stab_fast_{mode}_E{E:g}_T{press_s:g}{tag}"
    scene = bench.scene_variant(PRESS, {"body.material.youngs_modulus_Pa": E,
                                        "device.trajectory": script,
                                        "time.num_steps": int(math.ceil(end / dt)),
                                        **(edits or {})}, label)
    summary, frames, folder = bench.sim(scene, label, "--mode", mode)
    h = haptic(folder)
    visual_sink = max(0.0, max(top_plus_half - r["tool_z_m"] for r in frames))
    depth = top_plus_half - h["tool_z_m"]
    penetration = max(0.0, float(depth.max()) - visual_sink)
    tunnelled = bool(np.any((depth - visual_sink > PENETRATION_LIMIT_M) & (h["contacts"] == 0)))
    return {"mode": mode, "youngs_modulus_Pa": E, "press_s": press_s,
            "speed_m_s": depth_m / press_s, "travel_per_frame_m": depth_m / press_s * dt,
            "haptic_penetration_m": penetration, "visual_sink_m": visual_sink,
            "max_penetration_m": finite(summary["max_penetration_m"]),
            "peak_force_N": finite(summary["peak_force_N"]), "tunnelled": tunnelled,
            "fails": penetration > PENETRATION_LIMIT_M}


# The modes mapped over the whole E × speed grid: the default (hybrid, issue 25) and the paper's
# linear model alone; the others at compare_E only.
GRID_MODES = ["hybrid", "linear"]
FAST_STYLES = {"hybrid": ("C4", "P", "-", 8), "linear": ("C0", "o", "-", 7),
               "lcp": ("C1", "^", "--", 9), "coupling": ("C2", "s", ":", 5),
               "penalty": ("C3", "D", "-", 6)}


def fast_grid(quick):
    """(moduli Pa, press times s) of the E × speed grid, the other modes, their times and E."""
    if quick:
        return [5e6], [0.8, 0.005], ["lcp"], [0.005], 5e6
    times = [0.8, 0.2, 0.05, 0.02, 0.01, 0.005]
    return [5e4, 5e5, 5e6, 5e7], times, ["lcp", "coupling", "penalty"], times, 5e6


def fast_map(bench):
    moduli, times, others, other_times, compare_E = fast_grid(bench.quick)
    points = []
    for mode in GRID_MODES:
        for E in moduli:
            for T in times:
                bench.progress(f"stability: fast tool, {mode}, E {E:g} Pa, press in {T:g} s")
                points.append(fast_run(bench, mode, E, T))
    for mode in others:
        for T in other_times:
            bench.progress(f"stability: fast tool, {mode}, E {compare_E:g} Pa, press in {T:g} s")
            points.append(fast_run(bench, mode, compare_E, T))
    fig, axes = plt.subplots(1, len(GRID_MODES) + 1, figsize=(17.5, 4.8))
    for axis, mode in zip(axes, GRID_MODES):
        cell_map(axis, [p for p in points if p["mode"] == mode], "speed_m_s",
                 "youngs_modulus_Pa", lambda p: p["fails"],
                 lambda p: f"{1e3 * p['haptic_penetration_m']:.2f}",
                 lambda p: "tunnels" if p["tunnelled"] else "")
        axis.set(xlabel="press speed (m/s; 5 mm in 0.8–0.005 s)", ylabel="Young's modulus E (Pa)",
                 title=f"--mode {mode}" + (" (the default)" if mode == GRID_MODES[0] else "")
                 + ", 33 Hz: haptic tool penetration (mm)")
        axis.title.set_fontsize(9)
        axis.legend(handles=[Patch(color=STABLE_COLOR, label="≤ 1 mm"),
                             Patch(color=FAIL_COLOR, label="> 1 mm (fails)")],
                    fontsize=7, loc="upper left", framealpha=0.9)
    right = axes[-1]
    top = max(1e3 * p["haptic_penetration_m"] for p in points) * 1.15 + 0.5
    bottom = -0.04 * top
    right.axhspan(1e3 * PENETRATION_LIMIT_M, top, color=FAIL_COLOR, alpha=0.8, lw=0,
                  label="penetration > 1 mm")
    for mode in GRID_MODES + others:
        chosen = sorted([p for p in points if p["mode"] == mode and
                         p["youngs_modulus_Pa"] == compare_E], key=lambda p: p["speed_m_s"])
        color, marker, line, size = FAST_STYLES[mode]
        right.plot([p["speed_m_s"] for p in chosen],
                   [1e3 * p["haptic_penetration_m"] for p in chosen], marker=marker, ls=line,
                   color=color, ms=size, mfc="none" if mode == "lcp" else color,
                   label=f"--mode {mode}")
        for p in chosen:
            if p["tunnelled"]:
                right.plot(p["speed_m_s"], 1e3 * p["haptic_penetration_m"], "kx", ms=9)
    right.plot([], [], "kx", ls="", label="tunnelled (no contact in its model)")
    right.set(xscale="log", ylim=(bottom, top), xlabel="press speed (m/s)",
              ylabel="haptic tool penetration (mm)",
              title=f"E = {compare_E:g} Pa: penetration per mode")
    right.grid(True, which="both", alpha=0.3)
    right.legend(fontsize=7, loc="upper left")
    save_figure(fig, bench.path("stability_fast_tool.png"))
    figure = {"file": "stability_fast_tool.png",
              "caption": "A stiff body under a fast tool (block_press, device pressed 5 mm in "
                         "0.8–0.005 s): the haptic tool's penetration beyond the visual tool's "
                         "sink, over E × speed for the default mode (hybrid) and the paper's "
                         "linear model alone, and per mode at 5 MPa; red above 1 mm."}
    return {"scene": PRESS + " (device pressed 5 mm in press_s, scripted)",
            "criterion": f"haptic_penetration_m > {PENETRATION_LIMIT_M}", "points": points}, figure


def fast_markdown(result):
    points = result["points"]
    linear = [p for p in points if p["mode"] == "linear"]
    fails = [p for p in linear if p["fails"]]
    slowest_fail = min((p["speed_m_s"] for p in fails), default=None)
    fastest_ok = max((p["speed_m_s"] for p in linear if not p["fails"]), default=None)
    modes = []
    for p in points:
        if p["mode"] not in modes:
            modes.append(p["mode"])
    moduli = sorted({p["youngs_modulus_Pa"] for p in linear})
    worst_pen = {mode: max(p["haptic_penetration_m"] for p in points if p["mode"] == mode)
                 for mode in modes}
    least_pen = {mode: min(p["haptic_penetration_m"] for p in points if p["mode"] == mode)
                 for mode in modes}
    # Since issue 13's smaller lcp models the frame couples through the body only the rows an
    # approach at haptic.lcp_reach_m_s engages within the frame; the others travel uncoupled, so
    # that a tool that starts faster between frames still meets them. Which of the two
    # explanations is printed follows the run's own figures.
    lcp_fails = worst_pen.get("lcp", 0.0) > PENETRATION_LIMIT_M
    hybrid = [p for p in points if p["mode"] == "hybrid"]
    hybrid_fails = [p for p in hybrid if p["fails"] or p["tunnelled"]]
    hybrid_text = ""
    if hybrid:
        hybrid_text = (
            "The default, hybrid, fails in " + f"{len(hybrid_fails)} of {len(hybrid)} cells "
            f"(E {min(p['youngs_modulus_Pa'] for p in hybrid):g} to "
            f"{max(p['youngs_modulus_Pa'] for p in hybrid):g} Pa, up to "
            f"{max(p['speed_m_s'] for p in hybrid):g} m/s; at most "
            f"{1e3 * max(p['haptic_penetration_m'] for p in hybrid):.2f} mm, "
            f"{sum(p['tunnelled'] for p in hybrid)} tunnelled): it holds the frame's active rows "
            "as the linear model does and switches the frame's other candidate rows on at 1 kHz, "
            "so a tool that arrives between frames meets a row. ")
    why = {"lcp": (" (a tool faster than haptic.lcp_reach_m_s between frames meets rows that its "
                   "model does not hold)" if lcp_fails else
                   " (its 1 kHz problem keeps the frame's inactive rows within the margin, those "
                   "it does not expect the tool to reach uncoupled)"),
           "coupling": " (the device feels the visual tool, which the frame's constraints hold)",
           "penalty": f", and at least {1e3 * least_pen.get('penalty', 0.0):.2f} mm even slowly: "
                      "it sinks by F/k into the frame's surface whatever the speed (a soft "
                      "0.6 N/mm spring, not tunnelling)"}
    md = [f"**Stiff body under a fast tool** ({result['scene']}; the haptic tool's penetration "
          "is its depth below the undeformed top minus the visual tool's; fails above "
          f"{1e3 * PENETRATION_LIMIT_M:g} mm; tunnels if that deep with no contact in its "
          "model). " + hybrid_text + "The paper's linear mode alone fails "
          + (f"from {slowest_fail:g} m/s ("
             + (f"fastest held: {fastest_ok:g} m/s)" if fastest_ok is not None else "none held)")
             + (f", at every E from {min(moduli):g} to {max(moduli):g} Pa" if len(moduli) > 1
                else "") + ": " if fails else "nowhere on the grid: ")
          + "its model holds only the contacts active at the last frame, so a tool that arrives "
          "between frames meets no row and sinks until the next frame pushes it out (β per "
          "frame). The visual frame's own penetration (max_penetration_m) stays at "
          f"{1e3 * max(p['max_penetration_m'] or 0.0 for p in points):.2f} mm."
          + "".join(f" {mode}: at most {1e3 * worst_pen[mode]:.2f} mm" + why.get(mode, "") + "."
                    for mode in modes if mode not in ("linear", "hybrid")), "",
          "| mode | E (Pa) | press (s) | speed (m/s) | haptic penetration (mm) | tunnelled | "
          "visual sink (mm) | peak force (N) |", "|---|---:|---:|---:|---:|---|---:|---:|"]
    for p in points:
        pen = f"{1e3 * p['haptic_penetration_m']:.2f}"
        md.append(f"| {p['mode']} | {p['youngs_modulus_Pa']:g} | {p['press_s']:g} | "
                  f"{p['speed_m_s']:.3g} | " + (f"**{pen}**" if p["fails"] else pen)
                  + f" | {'yes' if p['tunnelled'] else 'no'} | {1e3 * p['visual_sink_m']:.2f} | "
                  f"{p['peak_force_N']:.2f} |")
    md.append("")
    return md
