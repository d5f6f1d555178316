#!/usr/bin/env bash
# Cross-process checks of `hapsim run` (visual process) + `hapsim haptic` (spawned, 1 kHz) over
# LCM on scenes/block_press.yaml (and, check 11, probe and peg_in_hole; run by ctest from the repository root). Traffic stays on this
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
#  8. run isolation (issue 9): two runs at once on one URL each agree with the in-process run as
#     check 1 does, each log holds its own run only and replays bit for bit from another folder,
#     and each process reports the other run's traffic;
#  9. self-contained logs: replay from another folder uses the log's own scene text (an edit of
#     the scene file after the run changes nothing, while --scene with the edited file does), and
#     a changed or missing tool mesh file is an error naming it; a log whose first event claims
#     2^31 - 1 bytes (replay once segfaulted) is an error naming the byte;
# 10. a hostile publisher on the run's URL and run id changes no force (see the check);
# 11. the source papers' 1 kHz modes across processes (docs/HAPTIC_MODES.md): scenes/probe.yaml in
#     its godobject mode and scenes/peg_in_hole.yaml in the penalty mode, the frame's world
#     carried by each contact model, and scenes/retraction.yaml, organs.yaml and drop.yaml (a
#     grasp's bilateral rows, contact between two organs, an instrument that falls; issue 28) in
#     the default mode: each log replays bit for bit and its forces agree with
#     `hapsim sim` in that mode as check 1's do; the retraction log scores its task reached with
#     no tissue torn, and a run with the grip limit cut scores the tissue torn.
# Usage: two_process_test.sh HAPSIM HAPSIM_EXAMPLE_DRIVER
set -euo pipefail
hapsim="$(realpath "$1")"
driver="$(realpath "$2")"
source "$(dirname "$0")/local_network.sh" "$0" "$@"  # url, work, fail
scene=scenes/block_press.yaml
mkdir "$work/elsewhere"  # replays run from here: a folder without the scene

# A run of block_press is whole: one haptic step per millisecond of the 3 s script in its haptic
# summary, and in its log (CSV of `hapsim replay --csv`) at most 10 missing. (A step whose
# HAPTIC_STATE datagram was lost is missing from the log; replay re-creates it.)
run_is_whole() {
  /usr/bin/python3 - "$1" "$2" <<'PY'
import csv, json, sys
summary = json.load(open(sys.argv[1]))
logged = list(csv.DictReader(open(sys.argv[2])))
assert summary["steps"] == 3000, summary["steps"]
assert len(logged) >= 2990, f"{3000 - len(logged)} steps missing from the log"
PY
}

# A whole run whose device forces agree with the in-process simulator's: RMS within the
# tolerance below and the peak within 5% (steps missing from the log are left out).
agrees_with_in_process() {
  run_is_whole "$1" "$2" || return 1
  /usr/bin/python3 - "$1" "$2" "$work/sim/haptic.csv" <<'PY'
import csv, json, math, sys
summary = json.load(open(sys.argv[1]))
logged = list(csv.DictReader(open(sys.argv[2])))
inproc = list(csv.DictReader(open(sys.argv[3])))
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
}

# A disturbed run is repeated up to three times. Under a sanitizer once: its frames fall behind the
# haptic clock, so the forces cannot agree, and each attempt costs a minute or more. For the same
# reason the sanitized run compares no forces with a reference run (checks 1, 6, 10 and 11)
# and makes no in-process reference run: it checks the runs, their logs and bit-exact replays,
# under the sanitizer; the agreement is the unsanitized run's to check. (Under ASan the test took
# 256 s with them and ended inconclusive, skipped; 153-160 s without, passed: AMD VM, 2026-11-29.)
attempts=3
compare_forces=1
if [ -n "${HAPSIM_SANITIZED:-}" ]; then
  attempts=1
  compare_forces=0
  echo "sanitized build: one attempt a run, and no force agreement with the in-process simulator"
fi

# What a logged run of block_press must pass: whole, and (unsanitized) agreeing with `hapsim sim`.
run_checks_out() {
  if [ "$compare_forces" -eq 1 ]; then agrees_with_in_process "$@"; else run_is_whole "$@"; fi
}

# 1. A whole run, logged. A host that stalls the machine can still make the kernel drop a
# datagram (the log then misses a step, which replay reports) or delay the models beyond what
# the tolerance below allows: either way the run is repeated ($attempts times at most), and said
# so. A replay that differs from a complete log fails at once.
[ "$compare_forces" -eq 0 ] ||  # the scene's mode, as `run` takes it
  "$hapsim" sim "$scene" --out "$work/sim" > /dev/null
good=0
for attempt in $(seq "$attempts"); do
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
  if ! run_checks_out "$work/haptic.json" "$work/logged.csv"; then
    echo "attempt $attempt: forces outside the tolerance (a run the host disturbed?); running again"
    continue
  fi
  good=1
  break
done
# Three disturbed attempts: the host cannot give the loop real-time conditions now. That is not a
# failure of the code; the test goes on with the other checks and ends as skipped (exit 77).
inconclusive=""
[ "$good" -eq 1 ] || inconclusive="$attempts run(s) lost datagrams or were disturbed by the host"

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
# Started by hand (as on a device's own machine), so both are given the same run id.
"$hapsim" haptic "$scene" --lcm-url "$url" --run-id 4a --duration 3 --summary "$work/fade.json" \
  > "$work/fade_haptic.out" 2>&1 &
haptic_pid=$!
"$hapsim" run "$scene" --lcm-url "$url" --run-id 4a --no-spawn > /dev/null 2>&1 &
visual_pid=$!
# Killed 1.6 s into the haptic loop, which starts at the first model: a fixed 1.6 s from the
# start once killed a visual process still starting (ASan on a busy host) before any model.
for _ in $(seq 600); do
  grep -q "the loop starts" "$work/fade_haptic.out" 2> /dev/null && break
  sleep 0.1
done
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
sed 's/^  rate_hz: 1000$/  rate_hz: 1000\n  safety: {max_force_N: 2.0}/' "$scene" > "$work/clamped.yaml"
grep -q "max_force_N: 2.0" "$work/clamped.yaml" || fail "could not make the clamped scene"
# The logger is a separate process that must keep up with 3 kHz of messages while the haptic
# process runs at SCHED_FIFO: as root it gets a real-time priority below the haptic loop's, so a
# busy machine does not make it drop a datagram (that happened once on a loaded CI run).
logger=(lcm-logger --lcm-url="$url" --quiet --force "$work/stock.lcm")
if [ "$(id -u)" -eq 0 ] && command -v chrt > /dev/null; then logger=(chrt -f 10 "${logger[@]}"); fi
for attempt in $(seq "$attempts"); do
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
  [ "$attempt" -lt "$attempts" ] || inconclusive="${inconclusive:+$inconclusive; }$attempts lcm-logger run(s) lost datagrams"
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
for attempt in $(seq "$attempts"); do
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
  if [ "$replayed" -eq 1 ] && { [ "$compare_forces" -eq 0 ] ||
    /usr/bin/python3 - "$work/external.csv" "$work/hand.csv"; } <<'PY'
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
  [ "$attempt" -lt "$attempts" ] || inconclusive="${inconclusive:+$inconclusive; }$attempts external-driver run(s) disturbed"
done

# Checks 7 and 8 are about transport and timing (a stalled process's queue, two runs' isolation
# under four processes on two cores), not memory: their code is that of checks 1 and 10. Under a
# sanitizer, where every process runs several times slower, they would cost minutes and could
# only end inconclusive, so they are left to the unsanitized run.
if [ -n "${HAPSIM_SANITIZED:-}" ]; then
  echo "checks 7 and 8 (a stalled process, two runs at once) left to the unsanitized run"
else
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

  # 8. Two runs at once on one URL, the second started 0.3 s after the first (before run ids, each
  # haptic process took the other's models and device states: a 4.9 N peak against 3.1 N, and logs
  # holding both runs). Four processes share the two cores here, so a disturbed attempt is
  # repeated as in 1.
  for attempt in $(seq "$attempts"); do
    "$hapsim" run "$scene" --lcm-url "$url" --log "$work/a.lcm" --haptic-summary "$work/a.json" \
      > "$work/a.out" 2>&1 &
    a_pid=$!
    sleep 0.3
    "$hapsim" run "$scene" --lcm-url "$url" --log "$work/b.lcm" --haptic-summary "$work/b.json" \
      > "$work/b.out" 2>&1 || fail "second of two runs: $(cat "$work/b.out")"
    wait "$a_pid" || fail "first of two runs: $(cat "$work/a.out")"
    agreed=1
    for name in a b; do
      # Each process saw the other run and said so, once, and counted it.
      grep -q "hapsim run: warning: ignoring messages of another run" "$work/$name.out" ||
        fail "run $name did not report the other run: $(cat "$work/$name.out")"
      grep -q "hapsim haptic: ignored [0-9]* messages of other runs" "$work/$name.out" ||
        fail "haptic process $name did not report the other run: $(cat "$work/$name.out")"
      [ "$(grep -c "warning: ignoring messages of another run" "$work/$name.out")" -eq 2 ] ||
        fail "run $name warned more than once per process: $(cat "$work/$name.out")"
      # Its log replays bit for bit from a folder without the scene, holding its own run only.
      if ! (cd "$work/elsewhere" && "$hapsim" replay "../$name.lcm" --csv "../$name.csv") \
        > "$work/${name}_replay.out" 2>&1; then
        grep -qE "the log misses|is not in the log" "$work/${name}_replay.out" ||
          fail "replay of run $name: $(cat "$work/${name}_replay.out")"
        agreed=0
        continue
      fi
      grep -q "3000 haptic steps .* reproduced bit for bit .*scene from the log" \
        "$work/${name}_replay.out" || fail "replay of run $name: $(cat "$work/${name}_replay.out")"
      /usr/bin/python3 -c 'import json,sys; s=json.load(open(sys.argv[1])); assert s["foreign_messages"] > 0 and s["messages_rejected"] == 0, s' \
        "$work/$name.json" || fail "haptic summary $name: $(cat "$work/$name.json")"
      agrees_with_in_process "$work/$name.json" "$work/$name.csv" | sed "s/^/run $name: /" || agreed=0
    done
    [ "$agreed" -eq 1 ] && break
    echo "attempt $attempt: two runs at once lost a datagram or disagreed; running again"
    [ "$attempt" -lt "$attempts" ] || inconclusive="${inconclusive:+$inconclusive; }$attempts pair(s) of runs disturbed"
  done
  echo "two runs at once on one URL: each kept to its own run"
fi

# 9. Self-contained logs. A tool read from a mesh file (a 4 cm cube in place of the cylinder, ASCII
# STL) in a scene outside the repository; 1.2 s of the script, which presses it 3 mm in.
mkdir "$work/scene9"
/usr/bin/python3 - "$work/scene9/cube.stl" <<'PY'
import itertools, sys
h = 0.02
faces = []  # two counter-clockwise triangles per face, seen from outside
for axis in range(3):
    for sign in (-1, 1):
        u, v = [a for a in range(3) if a != axis]
        corners = []
        for du, dv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            p = [0.0] * 3
            p[axis], p[u], p[v] = sign * h, du * h, dv * h
            corners.append(p)
        n = [0.0] * 3
        n[axis] = sign
        # (u, v, axis) is right-handed for axis 0 and 2 and left-handed for axis 1
        if (sign > 0) != (axis == 1):
            order = [0, 1, 2, 0, 2, 3]
        else:
            order = [0, 2, 1, 0, 3, 2]
        faces += [(n, [corners[i] for i in order[:3]]), (n, [corners[i] for i in order[3:]])]
with open(sys.argv[1], "w") as out:
    out.write("solid cube\n")
    for n, tri in faces:
        out.write("facet normal %g %g %g\n outer loop\n" % tuple(n))
        for p in tri:
            out.write("  vertex %.6f %.6f %.6f\n" % tuple(p))
        out.write(" endloop\nendfacet\n")
    out.write("endsolid cube\n")
PY
sed 's/^    cylinder: .*$/    mesh: {file: cube.stl}/' "$scene" > "$work/scene9/cube_press.yaml"
grep -q "file: cube.stl" "$work/scene9/cube_press.yaml" || fail "could not make the mesh-tool scene"
"$hapsim" run "$work/scene9/cube_press.yaml" --lcm-url "$url" --duration 1.2 --log "$work/cube.lcm" \
  > "$work/cube.out" 2>&1 || fail "mesh-tool run: $(cat "$work/cube.out")"
replay_cube() { (cd "$work/elsewhere" && "$hapsim" replay ../cube.lcm "$@") > "$work/cube_replay.out" 2>&1; }
replay_cube || fail "replay of the mesh-tool run: $(cat "$work/cube_replay.out")"
grep -q "1200 haptic steps .* reproduced bit for bit .*scene from the log" "$work/cube_replay.out" ||
  fail "replay of the mesh-tool run: $(cat "$work/cube_replay.out")"
# The scene file edited after the run (a stiffer coupling): replay still reproduces the run from
# the log's own text; the edited file given with --scene does not (so the edit is one that counts).
sed -i 's/k_lin_N_m: 1000/k_lin_N_m: 3000/' "$work/scene9/cube_press.yaml"
replay_cube || fail "replay after the scene was edited: $(cat "$work/cube_replay.out")"
set +e
replay_cube --scene "$work/scene9/cube_press.yaml"
status=$?
set -e
[ "$status" -ne 0 ] && grep -q "differs" "$work/cube_replay.out" ||
  fail "replay with the edited scene should differ: $(cat "$work/cube_replay.out")"
# The tool mesh changed (one more facet line's worth of text), then missing: exit 2, naming it.
echo "solid extra" >> "$work/scene9/cube.stl"
set +e
replay_cube
status=$?
set -e
[ "$status" -eq 2 ] && grep -q "cube.stl.*changed since the run" "$work/cube_replay.out" ||
  fail "a changed tool mesh should be an error naming it (exit $status): $(cat "$work/cube_replay.out")"
rm "$work/scene9/cube.stl"
set +e
replay_cube
status=$?
set -e
[ "$status" -eq 2 ] && grep -q "cube.stl.*missing" "$work/cube_replay.out" ||
  fail "a missing tool mesh should be an error naming it (exit $status): $(cat "$work/cube_replay.out")"
# A log whose first event claims 2^31 - 1 bytes of data: an error naming the byte, not a crash.
/usr/bin/python3 -c 'import struct,sys; open(sys.argv[1],"wb").write(struct.pack(">IqqII", 0xEDA1DA01, 0, 0, 12, 2**31 - 1) + b"DEVICE_STATE" + bytes(16))' \
  "$work/huge.lcm"
set +e
"$hapsim" replay "$work/huge.lcm" > "$work/huge.out" 2>&1
status=$?
set -e
[ "$status" -eq 2 ] && grep -q "huge.lcm.*truncated or corrupt.*event at byte 0" "$work/huge.out" ||
  fail "a log claiming 2^31 - 1 bytes (exit $status): $(cat "$work/huge.out")"
echo "self-contained logs: replay from another folder, after a scene edit; changed and missing files named"

# 10. A hostile publisher on the run's own URL and run id: junk, a contact model claiming
# num_rows = -1 (lcm-gen's decode throws on it), one with a NaN offset, and a valid one of another
# run, 40 of each, sent mid-press as raw LCM datagrams. None may change a force: the run still
# agrees with the in-process one, every rejection is counted in the haptic summary, and the log
# (which keeps the run's malformed messages) replays bit for bit, skipping them as the live side did.
/usr/bin/python3 - "$work/run.lcm" "$work/hostile.bin" <<'PY'
import struct, sys
data = open(sys.argv[1], "rb").read()
pos = 0
while pos < len(data):  # the first CONTACT_MODEL of check 1's log
    _, _, _, clen, dlen = struct.unpack(">IqqII", data[pos:pos + 28])
    channel = data[pos + 28:pos + 28 + clen].decode()
    payload = data[pos + 28 + clen:pos + 28 + clen + dlen]
    pos += 28 + clen + dlen
    if channel == "CONTACT_MODEL":
        break
run_id = struct.pack(">q", 0x1234abcd)
model = bytearray(payload)
model[16:24] = run_id
negative_rows = bytearray(model)
negative_rows[-8:-4] = struct.pack(">i", -1)  # num_body_nodes (then num_objects ends it)
nan_offset = bytearray(model)
nan_offset[220:228] = struct.pack(">d", float("nan"))  # F_c0_N[0]
other_run = bytearray(payload)
other_run[16:24] = struct.pack(">q", 0x77)
junk = bytes(range(256)) * 2
messages = [("CONTACT_MODEL", junk), ("DEVICE_STATE", junk), ("CONTACT_MODEL", negative_rows),
            ("CONTACT_MODEL", nan_offset), ("CONTACT_MODEL", other_run)]
with open(sys.argv[2], "wb") as out:
    for channel, body in messages:
        out.write(struct.pack(">H", len(channel)) + channel.encode() + struct.pack(">I", len(body)) + body)
PY
# The sender starts first and sleeps: Python's own start-up, on a core the visual process needs,
# delayed frames by two periods in a first version of this check.
/usr/bin/python3 - "$work/hostile.bin" "$port" > "$work/sender.out" 2>&1 <<'PY' &
import socket, struct, sys, time
time.sleep(1.5)  # into the press
raw = open(sys.argv[1], "rb").read()
messages, pos = [], 0
while pos < len(raw):
    (clen,) = struct.unpack(">H", raw[pos:pos + 2]); channel = raw[pos + 2:pos + 2 + clen]
    (blen,) = struct.unpack(">I", raw[pos + 2 + clen:pos + 6 + clen])
    messages.append((channel, raw[pos + 6 + clen:pos + 6 + clen + blen])); pos += 6 + clen + blen
sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)  # this machine only
sequence = 0
for _ in range(40):
    for channel, body in messages:  # LCM's small-message datagram: "LC02", sequence, channel\0, data
        sock.sendto(struct.pack(">II", 0x4C433032, 1000000 + sequence) + channel + b"\0" + body,
                    ("239.255.76.67", int(sys.argv[2])))
        sequence += 1
    time.sleep(0.01)
PY
sender_pid=$!
"$hapsim" run "$scene" --run-id 1234abcd --lcm-url "$url" --log "$work/hostile.lcm" \
  --haptic-summary "$work/hostile.json" > "$work/hostile.out" 2>&1 ||
  fail "run under a hostile publisher: $(cat "$work/hostile.out")"
wait "$sender_pid" || fail "hostile sender: $(cat "$work/sender.out")"
(cd "$work/elsewhere" && "$hapsim" replay ../hostile.lcm --csv ../hostile.csv) > "$work/hostile_replay.out" 2>&1 ||
  fail "replay of the run under a hostile publisher: $(cat "$work/hostile_replay.out")"
grep -q "reproduced bit for bit" "$work/hostile_replay.out" || fail "$(cat "$work/hostile_replay.out")"
grep -q "skipped [0-9]* messages of the run" "$work/hostile_replay.out" || fail "$(cat "$work/hostile_replay.out")"
/usr/bin/python3 - "$work/hostile.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
print(f"hostile publisher: {s['messages_rejected']} messages rejected, {s['foreign_messages']} of "
      f"another run ignored, largest force sent {s['max_force_sent_N']:.3f} N")
# 40 junk CONTACT_MODEL and 40 with num_rows = -1 fail decoding, 40 fail validation (junk
# DEVICE_STATE reaches no subscriber of the haptic process with a scripted device).
assert s["messages_rejected"] >= 120, s["messages_rejected"]
assert s["models_rejected"] >= 40, s["models_rejected"]
assert s["foreign_messages"] >= 40, s["foreign_messages"]
PY
run_checks_out "$work/hostile.json" "$work/hostile.csv" | sed "s/^/under a hostile publisher: /" ||
  inconclusive="${inconclusive:+$inconclusive; }the run under a hostile publisher lost steps or disagreed (host?)"

# 11. The papers' 1 kHz modes: the world travels with the models; and a grasp, organs that touch
# and an instrument that falls (issue 28: scenes/retraction.yaml, organs.yaml, drop.yaml,
# hybrid); replay and forces as above,
# with check 1's attempts (a lost datagram or a disturbed run is repeated); under a sanitizer the
# runs and their bit-exact replays are what it checks.
papers_mode_agrees() {  # summary, logged CSV, in-process CSV, label
  /usr/bin/python3 - "$@" <<'PY'
import csv, json, math, sys
summary = json.load(open(sys.argv[1]))
logged = list(csv.DictReader(open(sys.argv[2])))
inproc = list(csv.DictReader(open(sys.argv[3])))
assert summary["steps"] == len(inproc), (summary["steps"], len(inproc))
assert len(logged) >= len(inproc) - 10, f"{len(inproc) - len(logged)} steps missing from the log"
# As check 1: 0.1 N RMS, the peak within 5% (measured 0.028 N for probe, 0.002 N for the peg).
err = math.sqrt(sum((float(r[f"force_{a}_N"]) - float(inproc[int(r["step"])][f"force_{a}_N"])) ** 2
                    for r in logged for a in "xyz") / len(logged))
peak = lambda rows: max(math.sqrt(sum(float(r[f"force_{a}_N"]) ** 2 for a in "xyz")) for r in rows)
print(f"{sys.argv[4]} across processes: device force RMS difference from `hapsim sim` {err:.4f} N; "
      f"peaks {peak(logged):.3f} / {peak(inproc):.3f} N")
assert err < 0.1, err
assert abs(peak(logged) - peak(inproc)) < 0.05 * peak(inproc)
PY
}
for entry in "probe:godobject" "peg_in_hole:penalty" "retraction:hybrid" "organs:hybrid" \
  "drop:hybrid"; do
  name=${entry%%:*}
  mode=${entry#*:}
  [ "$compare_forces" -eq 0 ] ||
    "$hapsim" sim "scenes/$name.yaml" --mode "$mode" --out "$work/sim_$name" > /dev/null
  good=0
  for attempt in $(seq "$attempts"); do
    "$hapsim" run "scenes/$name.yaml" --mode "$mode" --lcm-url "$url" --log "$work/$name.lcm" \
      --haptic-summary "$work/$name.json" > "$work/$name.out" 2>&1 ||
      fail "$name $mode run: $(cat "$work/$name.out")"
    if ! (cd "$work/elsewhere" && "$hapsim" replay "../$name.lcm" --csv "../$name.csv") \
      > "$work/${name}_replay.out" 2>&1; then
      grep -qE "the log misses|is not in the log" "$work/${name}_replay.out" ||
        fail "$name replay: $(cat "$work/${name}_replay.out")"
      echo "$name attempt $attempt: a datagram was lost; running again"
      continue
    fi
    grep -q "reproduced bit for bit" "$work/${name}_replay.out" ||
      fail "$name replay: $(cat "$work/${name}_replay.out")"
    if [ "$compare_forces" -eq 1 ] && ! papers_mode_agrees "$work/$name.json" "$work/$name.csv" \
      "$work/sim_$name/haptic.csv" "$name $mode"; then
      echo "$name attempt $attempt: forces outside the tolerance (host?); running again"
      continue
    fi
    good=1
    break
  done
  [ "$good" -eq 1 ] || inconclusive="${inconclusive:+$inconclusive; }$attempts $name run(s) disturbed"
done

# The retraction task's score from its log (`hapsim view --score`, as the trainer scores it): the
# script reaches the target with nothing slipped from the jaws; with the grip limit cut to 0.05 N
# a point the scripted pull loads past it slips out, and the score says the tissue tore.
score_of() {  # log, score file, expect "torn" or "whole"
  "$hapsim" view "$1" --score "$2" > "$2.out" 2>&1 || fail "view --score $1: $(cat "$2.out")"
  /usr/bin/python3 - "$2" "$3" <<'PY'
import json, sys
score = json.load(open(sys.argv[1]))
print(f"retraction score ({sys.argv[2]}): reached {score['targets_reached']}, "
      f"peak pull {score['peak_force_N']:.3f} N, slipped {score['grip_slipped_points']}")
if sys.argv[2] == "whole":
    assert score["completed"] and score["grip_slipped_points"] == 0 and not score["tissue_torn"], score
else:
    assert score["grip_slipped_points"] >= 1 and score["tissue_torn"] and not score["completed"], score
PY
}
score_of "$work/retraction.lcm" "$work/retraction_score.json" whole || fail "the retraction score"
sed 's/max_force_N: 0.6 /max_force_N: 0.05/' scenes/retraction.yaml > "$work/torn.yaml"
grep -q "max_force_N: 0.05" "$work/torn.yaml" || fail "could not cut the grip limit"
"$hapsim" run "$work/torn.yaml" --lcm-url "$url" --log "$work/torn.lcm" > "$work/torn.out" 2>&1 ||
  fail "torn retraction run: $(cat "$work/torn.out")"
score_of "$work/torn.lcm" "$work/torn_score.json" torn || fail "the torn retraction's score"

if [ -n "$inconclusive" ]; then
  echo "SKIPPED (inconclusive): $inconclusive; every other check passed"
  exit 77
fi
echo "two-process checks passed"
