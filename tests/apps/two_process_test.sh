#!/usr/bin/env bash
# Cross-process checks of `hapsim run` (visual process) + `hapsim haptic` (spawned, 1 kHz) over
# LCM on scenes/block_press.yaml (run by ctest from the repository root). Traffic stays on this
# machine: inside a private network namespace when root (unshare -n, loopback up, a multicast
# route on lo), otherwise on a port unique to this test run with ttl=0.
#  1. a whole run completes (exit 0), the haptic process ran one step per millisecond of the
#     script, and its device forces agree with the in-process simulator (`hapsim sim`) within
#     the tolerance message timing allows (see the comment at the check);
#  2. `hapsim replay` of that log reproduces every logged force bit for bit; a truncated log is
#     a clear error (exit 2);
#  3. killing the haptic process mid-run makes `hapsim run` report it and exit non-zero;
#  4. killing the visual process mid-run: the haptic force fades to zero within the model stale
#     threshold;
#  5. a force limit below the scene's peak, recorded by the stock lcm-logger: that log replays
#     bit for bit too, and no force beyond the clamp was sent in the whole run. (The stock
#     lcm-logger keeps LCM's default of 30 messages waiting per subscription and drops beyond
#     that when it is held off the CPU for 15 ms at 2 kHz; `hapsim run --log` keeps 10,000.)
#  6. the external-driver protocol (docs/DEVICE.md): `hapsim run --device external` with
#     hapsim_example_driver renders the forces of `hapsim run --device hand`, and its log
#     replays bit for bit.
#  7. the visual process stopped (SIGSTOP) for 60 ms mid-run still logs every message: ~120
#     arrive meanwhile, four times the 30 LCM lets a subscription hold by default (KeepQueued).
# Usage: two_process_test.sh HAPSIM HAPSIM_EXAMPLE_DRIVER
set -euo pipefail
hapsim="$(realpath "$1")"
driver="$(realpath "$2")"
if [ -z "${HAPSIM_IN_NETNS:-}" ] && [ "$(id -u)" -eq 0 ] && unshare -n true 2>/dev/null; then
  exec env HAPSIM_IN_NETNS=1 unshare -n bash -c \
    'ip link set lo up && ip route add 224.0.0.0/4 dev lo && exec "$0" "$@"' "$0" "$@"
fi
port=$((20000 + $$ % 20000))
url="udpm://239.255.76.67:$port?ttl=0&recv_buf_size=4194304"
# Logs on tmpfs when there is one: a log writer stalled by a busy disk would drop datagrams.
work=$(mktemp -d -p /dev/shm 2> /dev/null || mktemp -d)
trap 'kill $(jobs -p) 2> /dev/null || true; rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
scene=scenes/block_press.yaml

# 1. A whole run, logged. A host that stalls the machine can still make the kernel drop a
# datagram (the log then misses a step, which replay reports) or delay the models beyond what
# the tolerance below allows: either way the run is repeated, up to three times, and said so. A replay that differs
# from a complete log fails at once; three failed attempts fail the test.
"$hapsim" sim "$scene" --mode linear --out "$work/sim" > /dev/null
good=0
for attempt in 1 2 3; do
  "$hapsim" run "$scene" --lcm-url "$url" --log "$work/run.lcm" \
    --haptic-summary "$work/haptic.json" > "$work/run.out" 2>&1 || fail "run: $(cat "$work/run.out")"
  [ -s "$work/run.lcm" ] || fail "no log written"
  if ! "$hapsim" replay "$work/run.lcm" --csv "$work/logged.csv" > "$work/replay.out" 2>&1; then
    grep -qE "the log misses|is not in the log" "$work/replay.out" ||
      fail "replay: $(cat "$work/replay.out"); run: $(grep -v "^  wrote" "$work/run.out")"
    echo "attempt $attempt: a datagram was lost ($(cat "$work/replay.out")); running again"
    continue
  fi
  grep -q "reproduced bit for bit" "$work/replay.out" || fail "replay: $(cat "$work/replay.out")"
  if ! /usr/bin/python3 - "$work/haptic.json" "$work/logged.csv" "$work/sim/haptic.csv" <<'PY'
import csv, json, math, sys
summary = json.load(open(sys.argv[1]))
logged = list(csv.DictReader(open(sys.argv[2])))
inproc = list(csv.DictReader(open(sys.argv[3])))
# One haptic step per millisecond of the 3 s script. (A step whose HAPTIC_STATE datagram was lost
# is missing from the log; replay re-creates it, and it is left out of the comparison below.)
assert summary["steps"] == 3000, summary["steps"]
assert len(logged) >= 2990, f"{3000 - len(logged)} steps missing from the log"
# Forces against the in-process run, where frame k's model is used from step 30k on. Across
# processes frame k starts once the haptic process has published step 30k − 1 and its model
# arrives one frame computation plus transport later (median 9 steps on an idle machine, more when
# the frame computes slowly), so the haptic tool runs a few ms longer on each previous model.
# Tolerance 0.1 N RMS over the run, 3% of the 3.1 N peak: measured 0.019–0.030 N on an idle
# machine and 0.073 N while a -j2 build competed for both cores (docs/BENCHMARKS.md). The peak
# within 5%.
err = math.sqrt(sum((float(r[f"force_{a}_N"]) - float(inproc[int(r["step"])][f"force_{a}_N"])) ** 2
                    for r in logged for a in "xyz") / len(logged))
peak = lambda rows: max(abs(float(r["force_z_N"])) for r in rows)
print(f"device force RMS difference from the in-process run: {err:.4f} N; peaks "
      f"{peak(logged):.3f} / {peak(inproc):.3f} N")
assert err < 0.1, err
assert abs(peak(logged) - peak(inproc)) < 0.05 * peak(inproc)
PY
  then
    echo "attempt $attempt: forces outside the tolerance (a run the host disturbed?); running again"
    continue
  fi
  good=1
  break
done
# Three disturbed attempts: the host cannot give the loop real-time conditions now. That is not a
# failure of the code; the test goes on with the other checks and ends as skipped (exit 77).
inconclusive=""
[ "$good" -eq 1 ] || inconclusive="three runs lost datagrams or were disturbed by the host"

# 2. A truncated log, as a recording cut off mid-write leaves it: exit 2 and a message naming it.
# The last 10 bytes go, so the cut lies inside the last event whatever the sizes (every event's
# header alone is 24 bytes); a cut at half the size once landed on an event boundary, which
# leaves a complete, shorter log.
head -c $(( $(stat -c %s "$work/run.lcm") - 10 )) "$work/run.lcm" > "$work/cut.lcm"
set +e
"$hapsim" replay "$work/cut.lcm" > "$work/cut.out" 2>&1
status=$?
set -e
[ "$status" -eq 2 ] || fail "truncated log should exit 2, got $status: $(cat "$work/cut.out")"
grep -q "cut.lcm.*truncated or corrupt" "$work/cut.out" || fail "message: $(cat "$work/cut.out")"

# 3. Kill the haptic process mid-run: `hapsim run` reports it and exits non-zero.
"$hapsim" run "$scene" --lcm-url "$url" > "$work/kill_haptic.out" 2>&1 &
run_pid=$!
sleep 1.5
pkill -KILL -f "hapsim haptic $scene --lcm-url udpm://239.255.76.67:$port" || fail "no haptic process to kill"
set +e
wait "$run_pid"
status=$?
set -e
[ "$status" -ne 0 ] || fail "run should fail when the haptic process dies"
grep -q "haptic process was killed by signal" "$work/kill_haptic.out" ||
  fail "message: $(cat "$work/kill_haptic.out")"

# 4. Kill the visual process mid-run: the haptic force fades to zero within model_stale_s.
"$hapsim" haptic "$scene" --lcm-url "$url" --duration 3 --summary "$work/fade.json" \
  > "$work/fade_haptic.out" 2>&1 &
haptic_pid=$!
"$hapsim" run "$scene" --lcm-url "$url" --no-spawn > /dev/null 2>&1 &
visual_pid=$!
sleep 1.6
kill -KILL "$visual_pid"
wait "$visual_pid" 2> /dev/null || true  # killed on purpose
wait "$haptic_pid" || fail "haptic process failed: $(cat "$work/fade_haptic.out")"
grep -q "fade-out after the last model" "$work/fade_haptic.out" || fail "$(cat "$work/fade_haptic.out")"
/usr/bin/python3 - "$work/fade.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
fade = s["fade_after_last_model_s"]
print(f"force faded to zero {1e3 * fade:.0f} ms after the last model (stale threshold {1e3 * s['model_stale_s']:.0f} ms)")
assert fade is not None and fade <= s["model_stale_s"] + 1e-9, (fade, s["model_stale_s"])
assert s["force_after_stale_N"] == 0.0, s["force_after_stale_N"]
PY
# 5. Clamped at 2 N (the run peaks at 3.1 N), logged by the stock lcm-logger.
sed 's/^  mode: linear$/  mode: linear\n  safety: {max_force_N: 2.0}/' "$scene" > "$work/clamped.yaml"
grep -q "max_force_N: 2.0" "$work/clamped.yaml" || fail "could not make the clamped scene"
# The logger is a separate process that must keep up with 3 kHz of messages while the haptic
# process runs at SCHED_FIFO: as root it gets a real-time priority below the haptic loop's, so a
# busy machine does not make it drop a datagram (that happened once on a loaded CI run).
logger=(lcm-logger --lcm-url="$url" --quiet --force "$work/stock.lcm")
if [ "$(id -u)" -eq 0 ] && command -v chrt > /dev/null; then logger=(chrt -f 10 "${logger[@]}"); fi
for attempt in 1 2 3; do
  "${logger[@]}" > /dev/null 2>&1 &
  logger_pid=$!
  sleep 0.5
  "$hapsim" run "$work/clamped.yaml" --lcm-url "$url" > "$work/clamped.out" 2>&1 ||
    fail "clamped run: $(cat "$work/clamped.out")"
  sleep 0.3
  kill -INT "$logger_pid"
  wait "$logger_pid" || true
  "$hapsim" replay "$work/stock.lcm" --csv "$work/stock.csv" > "$work/stock_replay.out" 2>&1 && break
  grep -qE "the log misses|is not in the log" "$work/stock_replay.out" ||
    fail "replay of the lcm-logger log: $(cat "$work/stock_replay.out")"
  echo "attempt $attempt: lcm-logger lost a datagram; running again"
  [ "$attempt" -lt 3 ] || inconclusive="${inconclusive:+$inconclusive; }three lcm-logger runs lost datagrams"
done
/usr/bin/python3 - "$work/stock.csv" <<'PY'
import csv, math, sys
rows = list(csv.DictReader(open(sys.argv[1])))
assert len(rows) >= 2990, len(rows)
peak = max(math.sqrt(sum(float(r[f"force_{a}_N"]) ** 2 for a in "xyz")) for r in rows)
print(f"run clamped at 2 N: largest force sent {peak:.6f} N")
assert peak <= 2.0 + 1e-12, peak
assert peak > 2.0 - 1e-6, "the clamp should have been reached"
PY
# 6. An external driver: the example driver closes the loop with the same simulated hand as
# `--device hand`, but in its own process, its states and forces over LCM. The loop through LCM
# delays each force by about one step, and the driver's script starts when it sees the loop run
# (a step or two after the loop's own start); both runs also carry their own frame timing (the
# models' ages), so the reference is not exact either. Measured 0.007–0.047 N RMS over 18 runs;
# tolerance 0.08 N, ~10% of the 0.85 N peak, well below what a broken protocol gives (a driver
# whose script ran 0.2 s ahead of the loop: 0.24 N). A disturbed run is repeated, as in 1.
for attempt in 1 2 3; do
  "$hapsim" run "$scene" --device external --lcm-url "$url" --log "$work/external.lcm" \
    > "$work/external.out" 2>&1 &
  run_pid=$!
  "$driver" "$scene" --lcm-url "$url" > "$work/driver.out" 2>&1 || fail "driver: $(cat "$work/driver.out")"
  wait "$run_pid" || fail "external run: $(cat "$work/external.out")"
  "$hapsim" run "$scene" --device hand --lcm-url "$url" --log "$work/hand.lcm" > "$work/hand.out" 2>&1 ||
    fail "hand run: $(cat "$work/hand.out")"
  replayed=1
  for name in external hand; do
    if ! "$hapsim" replay "$work/$name.lcm" --csv "$work/$name.csv" > "$work/${name}_replay.out" 2>&1; then
      grep -qE "the log misses|is not in the log" "$work/${name}_replay.out" ||
        fail "replay of the $name run: $(cat "$work/${name}_replay.out")"
      replayed=0
    fi
  done
  if [ "$replayed" -eq 1 ] && /usr/bin/python3 - "$work/external.csv" "$work/hand.csv" <<'PY'
import csv, math, sys
external = list(csv.DictReader(open(sys.argv[1])))
hand = list(csv.DictReader(open(sys.argv[2])))
assert len(external) == len(hand) == 3000, (len(external), len(hand))
err = math.sqrt(sum((float(e[f"force_{a}_N"]) - float(h[f"force_{a}_N"])) ** 2
                    for e, h in zip(external, hand) for a in "xyz") / len(hand))
peak = max(abs(float(h["force_z_N"])) for h in hand)
print(f"external driver vs in-process hand: device force RMS difference {err:.4f} N (peak {peak:.3f} N)")
assert peak > 0.5, "the hand should have pressed the block"
assert err < 0.08, err
PY
  then
    break
  fi
  echo "attempt $attempt: the external-driver run lost a datagram or disagreed; running again"
  [ "$attempt" -lt 3 ] || inconclusive="${inconclusive:+$inconclusive; }three external-driver runs disturbed"
done

# 7. A stalled receive thread keeps every message: SIGSTOP holds the whole visual process for
# 60 ms while the haptic process publishes 2 kHz of states; the kernel keeps the datagrams
# (4 MB socket buffer) and, once resumed, LCM must queue all ~120 for the log's subscription. At
# LCM's default capacity this run's log missed a step; no retry: the kernel cannot lose 40 kB.
"$hapsim" run "$scene" --lcm-url "$url" --log "$work/stopped.lcm" > "$work/stopped.out" 2>&1 &
run_pid=$!
sleep 1.5
kill -STOP "$run_pid"
sleep 0.06
kill -CONT "$run_pid"
wait "$run_pid" || fail "stopped run: $(cat "$work/stopped.out")"
"$hapsim" replay "$work/stopped.lcm" > "$work/stopped_replay.out" 2>&1 ||
  fail "a 60 ms stall of the visual process lost messages: $(cat "$work/stopped_replay.out")"
grep -q "3000 haptic steps .* reproduced bit for bit" "$work/stopped_replay.out" ||
  fail "stopped run's replay: $(cat "$work/stopped_replay.out")"
echo "visual process stopped for 60 ms: its log still holds every step"

if [ -n "$inconclusive" ]; then
  echo "SKIPPED (inconclusive): $inconclusive; every other check passed"
  exit 77
fi
echo "two-process checks passed"
