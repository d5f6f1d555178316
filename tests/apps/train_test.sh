#!/usr/bin/env bash
# `hapsim train scenes/liver_palpation.yaml` used as a trainee uses it, in Xvfb, driven by
# xdotool (run by ctest from the repository root). The trainer prints where each target is on the
# screen and how far down the tool must go to touch it; the script moves the mouse there, presses
# Down (depth) and holds, and takes screenshots with the trainer's s key. Checked:
#  1. the tool followed the mouse: in the screenshots the tool's blue is under the pointer, and it
#     moves right by the targets' pixel distance when the pointer does;
#  2. the tissue deformed where it was touched: around the first target the tissue is redder
#     (displacement colour) while pressed than before;
#  3. the scripted palpation reaches both targets and is scored so: the trainer ends by itself,
#     score.json says both reached, no time over the force limit, peak force within the limit;
#  4. the log is the session's record: `hapsim view LOG --score` gives the same score, and
#     `hapsim replay LOG` reproduces every force bit for bit.
# A session that misses the task while the host held the visual process below 95% of its frame
# rate is repeated, three times at most, then the test ends as skipped (77), as two_process_test
# does; missing it at full frame rate fails.
# Traffic stays on this machine: a private network namespace when root, else a unique port.
# Usage: train_test.sh HAPSIM   (HAPSIM_TRAIN_KEEP=DIR keeps the session's outputs there:
# scripts/bench_train.sh reads the haptic loop's summary from it)
set -euo pipefail
hapsim="$(realpath "$1")"
source "$(dirname "$0")/local_network.sh" "$0" "$@"  # url, work, fail, start_xvfb
start_xvfb

# One session: the trainer started, the palpation typed, the trainer's end awaited. Returns 0
# when the task was completed, 1 when not, 2 when not and the host held the visual process back
# (it ran fewer than 95% of the 50 Hz frames the session lasted: the models the 1 kHz loop
# rendered were late and the contact vibrated; seen once in a CI run, 45 Hz).
session() {
  rm -rf "$work/session"
  "$hapsim" train scenes/liver_palpation.yaml --out "$work/session" --lcm-url "$url" \
    --size 800x600 > "$work/train.out" 2>&1 &
  trainer=$!
  for _ in $(seq 200); do grep -q "mouse:" "$work/train.out" 2> /dev/null && break; sleep 0.1; done
  grep -q "mouse:" "$work/train.out" || fail "the trainer did not start: $(cat "$work/train.out")"
  window=$(xdotool search --onlyvisible --name "hapsim train: liver_palpation" | head -1)
  [ -n "$window" ] || fail "no trainer window"
  xdotool windowfocus --sync "$window"
  # "  target left_lobe: pointer at (327, 204), touches 16 mm down"
  read -r x1 y1 d1 <<< "$(target left_lobe)"
  read -r x2 y2 d2 <<< "$(target right_lobe)"
  [ -n "$x1" ] && [ -n "$x2" ] || fail "no target positions: $(cat "$work/train.out")"
  xdotool mousemove --sync "$x1" "$y1"
  # The simulation settles: the colours start from its shape at 1 s of simulated time, which a
  # slow host reaches later (a fixed 2.5 s once gave a "before" picture still coloured from rest).
  # Under ASan the trainer took 22-27 s to get there (three runs, 2026-11-27) and once more than
  # 30 s in CI: it is given 90 s there, 30 s otherwise.
  local wait_tenths=300
  [ -n "${HAPSIM_SANITIZED:-}" ] && wait_tenths=900
  for _ in $(seq "$wait_tenths"); do
    grep -q "displacements coloured from" "$work/train.out" && break
    sleep 0.1
  done
  grep -q "displacements coloured from" "$work/train.out" || fail "no displacement reference: $(cat "$work/train.out")"
  sleep 0.5
  shoot                 # 1: above the first target
  press "$d1"
  sleep 2.0
  shoot                 # 2: pressing it
  lift "$d1"
  sleep 0.8
  xdotool mousemove --sync "$x2" "$y2"
  sleep 1.0
  shoot                 # 3: above the second target
  press "$d2"
  if [ -n "${HAPSIM_SANITIZED:-}" ]; then
    # Under a sanitizer the frames are too slow for the task: end the session, and require only
    # that it ran and ended cleanly (a sanitizer report aborts with a non-zero exit).
    sleep 2
    xdotool key q
    wait "$trainer" || fail "the trainer failed under the sanitizer: $(cat "$work/train.out")"
    [ -s "$work/session/score.json" ] && [ -s "$work/session/run.lcm" ] || fail "no score or log"
    echo "train: ran and ended cleanly under the sanitizer; the timing checks are skipped"
    exit 77
  fi
  for _ in $(seq 150); do kill -0 "$trainer" 2> /dev/null || break; sleep 0.1; done
  kill -0 "$trainer" 2> /dev/null && xdotool key q
  wait "$trainer" || fail "the trainer failed: $(cat "$work/train.out")"
  grep -q "target left_lobe reached" "$work/train.out" &&
    grep -q "target right_lobe reached" "$work/train.out" && return 0
  /usr/bin/python3 - "$work/session/score.json" "$work/train.out" <<'PY' && return 1 || return 2
import json, re, sys
elapsed = json.load(open(sys.argv[1]))["elapsed_s"]
frames = int(re.search(r"hapsim run: (\d+) visual frames", open(sys.argv[2]).read()).group(1))
print(f"the visual process ran {frames} frames in {elapsed:.2f} s: {frames / (elapsed / 0.02):.0%} of 50 Hz")
sys.exit(0 if frames >= 0.95 * elapsed / 0.02 else 1)
PY
}
# "  target left_lobe: pointer at (327, 204), touches 16 mm down"
target() { grep "target $1:" "$work/train.out" | sed -E 's/.*\(([0-9]+), ([0-9]+)\), touches ([0-9]+) mm.*/\1 \2 \3/'; }
shoot() { xdotool key s; sleep 0.3; }
# Down until the device is 14 mm past the touch (2 mm a press): ~0.8 N on this tissue, the
# scripted palpation's depth. (20 mm past, the contact set of this coarse mesh flip-flops and the
# two-process rendering vibrates: the force left the band and a target was missed.)
press() { for _ in $(seq $((($1 + 14) / 2))); do xdotool key Down; sleep 0.05; done; }
lift() { for _ in $(seq $((($1 + 14) / 2))); do xdotool key Up; sleep 0.02; done; }

for attempt in 1 2 3; do
  result=0
  session || result=$?
  [ "$result" -eq 0 ] && break
  cat "$work/train.out"
  [ "$result" -eq 1 ] && fail "the task was not completed though the host kept the frame rate"
  echo "train: attempt $attempt disturbed by the host (the visual process fell behind)"
  if [ "$attempt" -eq 3 ]; then
    echo "train: skipped: three sessions disturbed by the host"
    exit 77
  fi
done
cat "$work/train.out"
grep -q "target left_lobe reached" "$work/train.out" && grep -q "target right_lobe reached" "$work/train.out" ||
  fail "targets not reached"

/usr/bin/python3 - "$work/session" "$x1" "$y1" "$x2" <<'PY'
import json, sys
import matplotlib.image as image
import numpy as np
folder, x1, y1, x2 = sys.argv[1], *map(int, sys.argv[2:5])
score = json.load(open(f"{folder}/score.json"))
print("score:", json.dumps({k: score[k] for k in ("targets_reached", "time_to_complete_s",
      "peak_force_N", "time_over_force_limit_s", "tool_path_length_m")}))
assert score["completed"] and score["targets_reached"] == 2, score
assert score["time_over_force_limit_s"] == 0.0 and score["peak_force_N"] <= score["force_limit_N"], score
assert score["time_to_complete_s"] < 30.0, score
shots = [image.imread(f"{folder}/screenshot_{k}.png")[:, :, :3] for k in (1, 2, 3)]
def tool_x(img):  # the tool's light blue (lit RGB ~ 120, 200, 230)
    r, g, b = img[:, :, 0], img[:, :, 1], img[:, :, 2]
    ys, xs = np.nonzero((b > r + 0.15) & (g > r + 0.1))
    assert len(xs) > 200, "no tool in the picture"
    return xs.mean()
# 1. The tool under the pointer, and moved with it.
print(f"tool at x {tool_x(shots[0]):.0f} under the pointer at {x1}; at {tool_x(shots[2]):.0f} under {x2}")
assert abs(tool_x(shots[0]) - x1) < 25 and abs(tool_x(shots[2]) - x2) < 25
# 2. Redness of the tissue (red over green) near the first target, before and while pressed.
def redness(img):
    r, g, b = img[:, :, 0], img[:, :, 1], img[:, :, 2]
    tissue = (r > g + 0.08) & (r > b + 0.08)
    near = np.zeros_like(tissue)
    near[y1:y1 + 250, max(0, x1 - 90):x1 + 90] = True
    return (r - g)[tissue & near].mean()
print(f"tissue redness near the first target: {redness(shots[0]):.3f} before, {redness(shots[1]):.3f} pressed")
assert redness(shots[1]) > redness(shots[0]) + 0.03
PY

# 4. The log: the same score, and a bit-exact replay.
"$hapsim" view "$work/session/run.lcm" --score "$work/log_score.json" > "$work/view.out" 2>&1 ||
  fail "view --score: $(cat "$work/view.out")"
/usr/bin/python3 - "$work/session/score.json" "$work/log_score.json" <<'PY'
import json, sys
live, log = (json.load(open(p)) for p in sys.argv[1:3])
for key in ("targets", "targets_reached", "completed", "time_to_complete_s", "peak_force_N",
            "time_over_force_limit_s", "tool_path_length_m"):
    assert live[key] == log[key], (key, live[key], log[key])
print("the log's score equals the live one")
PY
"$hapsim" replay "$work/session/run.lcm" > "$work/replay.out" 2>&1 ||
  fail "replay: $(cat "$work/replay.out")"
grep -q "bit for bit" "$work/replay.out" || fail "replay: $(cat "$work/replay.out")"
if [ -n "${HAPSIM_TRAIN_KEEP:-}" ]; then
  mkdir -p "$HAPSIM_TRAIN_KEEP" && cp -r "$work/session/." "$HAPSIM_TRAIN_KEEP/"
  cp "$work/train.out" "$HAPSIM_TRAIN_KEEP/train.out"
fi
echo "train: all checks passed"
