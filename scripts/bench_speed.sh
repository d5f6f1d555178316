#!/usr/bin/env bash
# Issue 13's speed-ups measured before and after in one run, each beside its accuracy.
#
#   [CASES="..."] scripts/bench_speed.sh [BASE_REV]   (default 4eceff2: main before issue 13's
#                                                      speed work)
#
# CASES: some of fem fem_step block_press block_press_hybrid block_press_large block_press_friction
# friction (all but block_press_hybrid by default, which needs a base with the hybrid mode, f688aed
# or later), e.g. issue 25's: CASES="block_press block_press_hybrid block_press_large
# block_press_friction" scripts/bench_speed.sh f688aed.
# Builds BASE_REV in a worktree (only the targets used; Release, -j2), then runs the same
# commands with both builds, the two of each pair one right after the other, on the same scene
# files (those checked out):
#   - `hapsim fem --bench` on the 3.6k- and 28.8k-tet blocks: 200 steps from rest, mean and
#     median, and the probe trajectory's largest difference from CHOLMOD (relative);
#   - fem_step_benchmark: the settled implicit step (CG + lagged Cholesky);
#   - `hapsim sim --mode linear` on block_press and block_press_large, `--mode hybrid` (the
#     default) on block_press for block_press_hybrid, and `--mode lcp` on
#     block_press_friction: the visual frame's median by contact count, and the device force's
#     RMS difference from the 1 kHz reference (block_press, computed once with the current build)
#     or between the two builds (the others, whose references take many minutes);
#   - haptic_friction_benchmark: the warm friction step at 200 contacts, 1 / 2 / 5 sweeps.
# Writes out/speed/speed.md (the tables for docs/BENCHMARKS.md) and speed.json. About 25 minutes
# on 2 cores; not part of ctest. Machines are shared and noisy: read ratios within this run.
set -euo pipefail
cd "$(dirname "$0")/.."
# One core, as issue 13's targets are stated (BLAS is openblas-serial). Debian's CHOLMOD is built
# with OpenMP and asks for 4 threads in its factorisations by a num_threads clause, which
# OMP_NUM_THREADS does not override; OMP_THREAD_LIMIT does. hapsim itself keeps CHOLMOD on the
# calling thread since 2026-11-26 (fem/cholmod_factor.cc); the limit holds older builds to it too.
export OMP_THREAD_LIMIT=1
# The tree the "after" build is made from, now (setup.sh builds it next): "-dirty" if it differs
# from its commit.
after_rev=$(git describe --always --dirty)
scripts/setup.sh
base_rev=${1:-4eceff2}
out=out/speed
mkdir -p "$out"
base_src=${TMPDIR:-/tmp}/hapsim-speed-base
if [ ! -d "$base_src/.git" ] && [ ! -f "$base_src/.git" ]; then
  git worktree add --detach "$base_src" "$base_rev"
fi
git -C "$base_src" checkout --detach -q "$base_rev"
cmake -S "$base_src" -B "$base_src/build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cases=${CASES:-fem fem_step block_press block_press_large block_press_friction friction}
targets=(hapsim)
[[ " $cases " == *" fem_step "* ]] && targets+=(fem_step_benchmark)
[[ " $cases " == *" friction "* ]] && targets+=(haptic_friction_benchmark)
cmake --build "$base_src/build" -j2 --target "${targets[@]}"
declare -A bin=([before]="$base_src/build" [after]=build)

# The reference of block_press, once (about 2 minutes).
[ -f "$out/reference/haptic.csv" ] ||
  build/apps/hapsim sim scenes/block_press.yaml --mode reference --out "$out/reference"

# One measurement with one build. The cases run in turn, each with the before build and then the
# after one, so that the two of a pair share the same minutes of this shared machine (run one
# build's set after the other's, a drift of the host between the halves once showed as a 1.5x
# "slow-down" of block_press that alternating runs did not confirm).
measure() {
  local run=$1 what=$2 b=${bin[$1]}
  mkdir -p "$out/$run"
  case $what in
    fem)
      "$b/apps/hapsim" fem --bench scenes/block_small.yaml scenes/block_large.yaml \
        --out "$out/$run/fem" > "$out/$run/fem.txt" ;;
    fem_step)
      "$b/tests/fem_step_benchmark" --benchmark_filter='BM_ImplicitStep/block:[12]/cholmod:0' \
        --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
        --benchmark_out="$out/$run/fem_step.json" --benchmark_out_format=json > /dev/null ;;
    block_press)
      "$b/apps/hapsim" sim scenes/block_press.yaml --mode linear --out "$out/$run/block_press" ;;
    block_press_hybrid)  # the default mode; a base before issue 25 has none
      "$b/apps/hapsim" sim scenes/block_press.yaml --mode hybrid \
        --out "$out/$run/block_press_hybrid" ;;
    block_press_large)
      local large=scenes/block_press_large.yaml
      if [ "$run" = before ]; then large=$before_large; fi
      "$b/apps/hapsim" sim "$large" --mode linear --out "$out/$run/block_press_large" ;;
    block_press_friction)
      "$b/apps/hapsim" sim scenes/block_press_friction.yaml --mode lcp \
        --out "$out/$run/block_press_friction" ;;
    friction)
      "$b/tests/haptic_friction_benchmark" --benchmark_filter='BM_HapticFrictionWarm/200/[125]$' \
        --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
        --benchmark_out="$out/$run/friction.json" --benchmark_out_format=json > /dev/null ;;
  esac
}
# block_press_large applies its factor in binary16, which the before build cannot read: that build
# runs a copy without the key, i.e. with its own default factor (double in 4eceff2). Written and
# checked before anything runs: a reformatted scene line would leave the key in and stop the run
# halfway.
before_large=$out/before/block_press_large.yaml
mkdir -p "$out/before"
sed 's/, factor_precision: half}/}/' scenes/block_press_large.yaml > "$before_large"
# A base that reads the key (issue 13's work on) runs the scene as it is.
if git -C "$base_src" grep -q factor_precision -- config/; then
  cp scenes/block_press_large.yaml "$before_large"
elif grep -q factor_precision "$before_large"; then
  echo "bench_speed.sh: scenes/block_press_large.yaml's factor_precision is not where the before" \
    "build's copy removes it (', factor_precision: half}' in the solver line)" >&2
  exit 2
fi
rm -rf "$out/before"/*/ "$out/after"/*/
for what in $cases; do
  for run in before after; do
    echo "== $what, $run (${bin[$run]})"
    measure "$run" "$what"
  done
done
# Debian's interpreter (the one python3-matplotlib is installed for; no chart here, but the same).
/usr/bin/python3 scripts/bench/speed_table.py "$out" "$base_rev" "$after_rev" | tee "$out/speed.md"
echo "speed: outputs in $out/"
