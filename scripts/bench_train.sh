#!/usr/bin/env bash
# The figures of the surgical scenes for docs/BENCHMARKS.md (issue 10):
#  - the visual frame of each on one core: `hapsim sim scenes/<scene>.yaml` (linear mode, its
#    scripted device), median and 95th percentile over the frames, contacts;
#  - the haptic loop during a trainer session: tests/apps/train_test.sh (Xvfb, xdotool palpating
#    both targets) keeps the session, whose haptic process wrote its summary: timing, the
#    overruns by cause (apps/haptic_command.cc LateStepCauses), the slowest step's solve.
# Prints a Markdown table. Usage: scripts/bench_train.sh
set -euo pipefail
cd "$(dirname "$0")/.."
hapsim=build/apps/hapsim
[ -x "$hapsim" ] || scripts/setup.sh
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
scenes="liver_palpation polyp"
for scene in $scenes; do "$hapsim" sim "scenes/$scene.yaml" --out "$work/$scene" > /dev/null; done
HAPSIM_TRAIN_KEEP="$work/train" tests/apps/train_test.sh "$hapsim" > "$work/train.log" 2>&1 ||
  { cat "$work/train.log"; exit 1; }
/usr/bin/python3 - "$work" $scenes <<'PY'
import csv, json, platform, statistics, subprocess, sys
work = sys.argv[1]
summary = json.load(open(f"{work}/train/haptic_summary.json"))
score = json.load(open(f"{work}/train/score.json"))
cpu = [l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")][0]
print(f"machine: {cpu}, {subprocess.run(['date', '-I'], capture_output=True, text=True).stdout.strip()}")
print("| figure | value |\n|---|---|")
for scene in sys.argv[2:]:
    frames = list(csv.DictReader(open(f"{work}/{scene}/frames.csv")))
    total = sorted(float(f["total_ms"]) for f in frames)
    contacts = max(int(f["contacts"]) for f in frames)
    print(f"| {scene} visual frame, median (in-process, {len(total)} frames) | {statistics.median(total):.2f} ms ({1000 / statistics.median(total):.0f} Hz) |")
    print(f"| ... 95th percentile | {total[int(0.95 * len(total))]:.2f} ms |")
    print(f"| ... most contacts in a frame | {contacts} |")
pe = summary["period_error"]
print(f"| trainer session: haptic period error p50 / p99 / max | {pe['p50_us']:.1f} / {pe['p99_us']:.1f} / {pe['max_us']:.0f} us |")
print(f"| ... overruns, zeroed steps, steps | {summary['overruns']}, {summary['zeroed_steps']}, {summary['steps']} |")
causes = summary["overrun_causes"]
print(f"| ... overruns by cause: own work / catching up / preempted / page faults / blocked / held off the CPU / woke late | "
      f"{causes['own_work']} / {causes['catching_up']} / {causes['preempted']} / {causes['page_faults']} / "
      f"{causes['blocked']} / {causes['held_off_cpu']} / {causes['woke_late']} |")
print(f"| ... the VM's steal over the session (/proc/stat, 10 ms a tick) | {summary['vm_steal_ms']:.0f} ms |")
slowest = summary["slowest_step"]
print(f"| ... slowest step: compute, rows, equality solves, factorisations | {slowest['compute_us']:.0f} us, "
      f"{slowest['rows']}, {slowest['iterations']}, {slowest['factorizations']} |")
lat = summary["model_latency"]
print(f"| ... model latency (publish to first use) p50 / p99 | {lat['p50_ms']:.2f} / {lat['p99_ms']:.2f} ms |")
print(f"| ... haptic step compute p50 / max | {summary['compute_p50_us']:.1f} / {summary['compute_max_us']:.0f} us |")
print(f"| ... task | {score['targets_reached']} of {score['targets_total']} targets in {score.get('time_to_complete_s', float('nan')):.2f} s, peak {score['peak_force_N']:.2f} N |")
PY
