#!/usr/bin/env bash
# Issue 28's frame and haptic-step costs (docs/BENCHMARKS.md "Issue 28"): scenes/retraction.yaml,
# organs.yaml and drop.yaml through `hapsim sim`, RUNS times each (default 3), and per run the
# median frame and its stages over the frames with the jaws closed and open (organs: open and
# resting on the lower organ, i.e. with active rows between them; drop: the instrument resting on
# the pad alone, 5.5-6.4 s, and pressed into it by the probe, 6.8-8.0 s), and the median haptic
# step.
#
#   scripts/bench_grasp.sh [RUNS]
set -euo pipefail
cd "$(dirname "$0")/.."
hapsim=build/apps/hapsim
[ -x "$hapsim" ] || scripts/setup.sh
runs=${1:-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for scene in retraction organs drop; do
  for i in $(seq "$runs"); do
    "$hapsim" sim "scenes/$scene.yaml" --out "$work/${scene}_$i" > /dev/null
  done
done
/usr/bin/python3 - "$work" "$runs" <<'PY'
import csv, json, statistics, sys
work, runs = sys.argv[1], int(sys.argv[2])
med = lambda rows, key: statistics.median(float(r[key]) for r in rows)
for scene in ("retraction", "organs"):
    for i in range(1, runs + 1):
        frames = list(csv.DictReader(open(f"{work}/{scene}_{i}/frames.csv")))
        summary = json.load(open(f"{work}/{scene}_{i}/summary.json"))
        held = [r for r in frames if int(r["grasped"]) > 0]
        free = [r for r in frames if int(r["grasped"]) == 0]
        resting = [r for r in free if int(r["active"]) > 0] if scene == "organs" else []
        line = (f"{scene} run {i}: jaws closed ({len(held)} frames) frame {med(held, 'total_ms'):.2f} ms "
                f"(free FEM {med(held, 'free_fem_ms'):.2f}, detection {med(held, 'detection_ms'):.3f}, "
                f"response {med(held, 'response_ms'):.2f}, model {med(held, 'model_ms'):.3f}); "
                f"jaws open {med(free, 'total_ms'):.2f} ms")
        if resting:
            line += (f"; resting on the lower organ ({len(resting)} frames, {med(resting, 'contacts'):.0f} "
                     f"rows) {med(resting, 'total_ms'):.2f} ms (detection {med(resting, 'detection_ms'):.3f}, "
                     f"response {med(resting, 'response_ms'):.2f})")
        print(line + f"; haptic step {summary['haptic_step_median_us']:.2f} us")
for i in range(1, runs + 1):
    frames = list(csv.DictReader(open(f"{work}/drop_{i}/frames.csv")))
    summary = json.load(open(f"{work}/drop_{i}/summary.json"))
    window = lambda a, b: [r for r in frames if a <= float(r["t_s"]) < b]
    parts = []
    for name, rows in (("resting on the pad", window(5.5, 6.4)), ("pressed", window(6.8, 8.0))):
        parts.append(f"{name} ({len(rows)} frames, {med(rows, 'contacts'):.0f} rows) "
                     f"{med(rows, 'total_ms'):.2f} ms (free FEM {med(rows, 'free_fem_ms'):.2f}, "
                     f"detection {med(rows, 'detection_ms'):.3f}, response {med(rows, 'response_ms'):.2f})")
    print(f"drop run {i}: " + "; ".join(parts) +
          f"; haptic step {summary['haptic_step_median_us']:.2f} us")
PY
