#!/usr/bin/env bash
# Fuzzes hapsim's readers and decoders of untrusted input (tests/fuzz/, issue 9).
#
#   scripts/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]     # default 60 s, every target
#
# Builds the libFuzzer targets with Debian's clang, ASan and UBSan in build-fuzz/ (only they and
# the libraries they link, -j2), then runs each for SECONDS_PER_TARGET on a copy of its committed
# corpus and regression inputs (tests/fuzz/corpus/T, tests/fuzz/regressions/T). New inputs that
# libFuzzer finds interesting stay in build-fuzz/fuzz-run/T/corpus, never in the committed corpus.
# Prints per target the executions, the inputs added and the findings.
#
# Exit 0: no finding. 1: a finding (a crash, a sanitizer report, a leak, a timeout, an allocation
# beyond -malloc_limit_mb or -rss_limit_mb); where the input was saved and how to keep it as a
# regression are printed. 2: usage, or the build or a fuzzer could not run.
#
# Environment: HAPSIM_FUZZ_BUILD_DIR (default build-fuzz; .ci/run gives build-asan, where
# HAPSIM_ASAN_FUZZ=1 scripts/test_sanitized.sh asan has built the targets already),
# HAPSIM_FUZZ_JOBS (build, default 2),
# HAPSIM_FUZZ_STRICT=1 (a reader's std::exception other than InputError is a finding too),
# HAPSIM_FUZZ_KEEP_GOING=1 (long sessions: libFuzzer's fork mode goes on past a finding, so that
# one known bug does not hide the next; each distinct finding is then listed once).
set -uo pipefail
cd "$(dirname "$0")/.."

readonly ALL_TARGETS="scene gmsh tetgen vtk obj stl surface_mesher lcm_log device_state device_force haptic_state
contact_model sim_frame run_info"
# Per-input limits: one input taking this long is a hang; an allocation above malloc_limit is an
# unbounded count field (issue 9: every reader checks counts against the bytes that remain).
readonly TIMEOUT_S=20 RSS_LIMIT_MB=2048 MALLOC_LIMIT_MB=512

seconds=${1:-60}
if ! [[ $seconds =~ ^[0-9]+$ ]] || ((seconds < 1)); then
  echo "usage: scripts/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]; targets:" $ALL_TARGETS >&2
  exit 2
fi
shift $(($# > 0 ? 1 : 0))
targets=${*:-$ALL_TARGETS}
for t in $targets; do
  if ! [[ " $(echo $ALL_TARGETS) " == *" $t "* ]]; then
    echo "fuzz.sh: unknown target '$t'; targets:" $ALL_TARGETS >&2
    exit 2
  fi
done

build=${HAPSIM_FUZZ_BUILD_DIR:-build-fuzz}
jobs=${HAPSIM_FUZZ_JOBS:-2}
start=$(date +%s)

# ---- build ----
if ! command -v clang++ > /dev/null; then
  echo "fuzz.sh: clang++ not found (Debian: apt-get install clang libclang-rt-dev)" >&2
  exit 2
fi
configure=(-S . -B "$build" -DHAPSIM_FUZZ=ON -DHAPSIM_BUILD_TESTS=ON -DHAPSIM_BUILD_BENCHMARKS=OFF)
if [[ ! -f $build/CMakeCache.txt ]]; then
  configure+=(-DHAPSIM_UNITY_LIBRARIES=ON)  # the libraries four files to a unit (CMakeLists.txt)
  # -O1 (ASan's usual level) builds in half the time of -O2; no NDEBUG: Eigen's and hapsim's
  # assertions are findings too. Line tables only, as the ASan build: a finding's stack still
  # names file and line, and the build is shorter than with full debug information.
  configure+=(-DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++
              -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only")
fi
log_dir=$build/fuzz-run
mkdir -p "$build"
if ! cmake "${configure[@]}" > "$build/fuzz-configure.log" 2>&1; then
  tail -20 "$build/fuzz-configure.log" >&2
  echo "fuzz.sh: configuring $build failed (log: $build/fuzz-configure.log)" >&2
  exit 2
fi
build_targets=()
for t in $targets; do build_targets+=(--target "fuzz_$t"); done
echo "fuzz.sh: building $(($(wc -w <<< "$targets"))) targets in $build (-j$jobs)"
if ! cmake --build "$build" -j "$jobs" "${build_targets[@]}" > "$build/fuzz-build.log" 2>&1; then
  grep -E "error|Error" -A3 "$build/fuzz-build.log" | head -40 >&2
  echo "fuzz.sh: build failed (full log: $build/fuzz-build.log)" >&2
  exit 2
fi
build_s=$(($(date +%s) - start))
echo "fuzz.sh: built in ${build_s} s; fuzzing each target for ${seconds} s"

# ---- fuzz ----
mkdir -p "$log_dir"
# The readers take paths, so the targets write each input to a file: in memory (/dev/shm) that
# costs microseconds, on this disk it cost 3 ms and cut the executions tenfold.
scratch_parent=/dev/shm
[[ -d $scratch_parent && -w $scratch_parent ]] || scratch_parent=$log_dir
scratch=$(mktemp -d "$scratch_parent/hapsim_fuzz.XXXXXX") || exit 2
trap 'rm -rf "$scratch"' EXIT
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=0:abort_on_error=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}

# The value of libFuzzer's final `stat::NAME: value` line in file $2.
final_stat() { sed -n "s/^stat::$1: *\([0-9]*\).*/\1/p" "$2" | tail -1; }

keep_going=()
if [[ ${HAPSIM_FUZZ_KEEP_GOING:-0} == 1 ]]; then
  keep_going=(-fork=1 -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1)
fi

# What input $2 of target $1 breaks: the first error line and the first frame in hapsim's code
# outside tests/fuzz (timeouts and out-of-memory inputs are named by kind, not re-run).
describe() {
  case $(basename "$2") in
    timeout-*) echo "timeout (an input ran over ${TIMEOUT_S} s)"; return ;;
    oom-* | malloc-*) echo "out of memory (over ${MALLOC_LIMIT_MB} MB at once or ${RSS_LIMIT_MB} MB)"; return ;;
  esac
  local out
  out=$(HAPSIM_FUZZ_TMPDIR=$scratch/$1 timeout 120 "$build/tests/fuzz/fuzz_$1" "$2" 2>&1)
  local what where
  what=$(grep -m1 -E 'runtime error|ERROR: (Address|Leak)Sanitizer|hapsim fuzz finding|terminate called|deadly signal' <<< "$out" | sed 's/^==[0-9]*==//')
  where=$(grep -E '^ *#[0-9]+ .* in .*/(core|fem|contact|device|config|messages|view|apps)/[a-z_]+\.(cc|h):[0-9]+' <<< "$out" | head -1 | sed 's/.* in \([^ (]*\).* \(\/[^ ]*\)$/\1 \2/')
  echo "${what:-unknown (rc only)}${where:+ | at $where}"
}

printf '\n%-14s %10s %9s %6s %5s %s\n' target executions exec/s added cov findings
status=0
findings_report=""
for t in $targets; do
  dir=$log_dir/$t
  rm -rf "$dir"
  dict=()
  [[ -f tests/fuzz/dict/$t.dict ]] && dict=(-dict="tests/fuzz/dict/$t.dict")
  mkdir -p "$dir/corpus" "$dir/artifacts" "$scratch/$t"
  for seeds in tests/fuzz/corpus/$t tests/fuzz/regressions/$t; do
    [[ -d $seeds ]] && find "$seeds" -maxdepth 1 -type f -exec cp {} "$dir/corpus/" \;
  done
  seeds_count=$(find "$dir/corpus" -type f | wc -l)
  # timeout: a guard in case libFuzzer itself does not stop (its per-input -timeout handles hangs).
  HAPSIM_FUZZ_TMPDIR=$scratch/$t timeout -k 10 $((seconds * 2 + 120)) \
    "$build/tests/fuzz/fuzz_$t" -max_total_time="$seconds" -print_final_stats=1 \
    -timeout=$TIMEOUT_S -rss_limit_mb=$RSS_LIMIT_MB -malloc_limit_mb=$MALLOC_LIMIT_MB \
    -artifact_prefix="$dir/artifacts/" "${dict[@]}" "${keep_going[@]}" "$dir/corpus" > "$dir/fuzz.log" 2>&1
  rc=$?
  execs=$(final_stat number_of_executed_units "$dir/fuzz.log")
  rate=$(final_stat average_exec_per_sec "$dir/fuzz.log")
  if ((${#keep_going[@]})); then  # fork mode prints "#EXECS: cov: C ... exec/s R ..." instead
    last=$(grep -E '^#[0-9]+: cov:' "$dir/fuzz.log" | tail -1)
    execs=$(sed -n 's/^#\([0-9]*\):.*/\1/p' <<< "$last")
    rate=$(sed -n 's/.*exec\/s \([0-9]*\).*/\1/p' <<< "$last")
  fi
  added=$(($(find "$dir/corpus" -type f | wc -l) - seeds_count))
  cov=$(grep -o 'cov: [0-9]*' "$dir/fuzz.log" | tail -1 | cut -d' ' -f2)
  artifacts=$(find "$dir/artifacts" -type f \( -name 'crash-*' -o -name 'leak-*' -o \
    -name 'timeout-*' -o -name 'oom-*' -o -name 'slow-unit-*' -o -name 'malloc-*' \) | sort)
  # slow-unit files are reports, not failures; everything else, and a failing exit, is a finding.
  failing=$(echo "$artifacts" | grep -v '/slow-unit-' | grep -v '^$')
  n=$(echo -n "$failing" | grep -c '^' || true)
  if ((rc != 0)) && ((n == 0)); then n=1; fi
  printf '%-14s %10s %9s %6s %5s %s\n' "$t" "${execs:-?}" "${rate:-?}" "$added" "${cov:-?}" "$n"
  if ((n > 0)); then
    status=1
    findings_report+=$'\n'"== fuzz_$t: exit $rc; log $dir/fuzz.log"$'\n'
    declare -A seen=()
    for a in $failing; do
      what=$(describe "$t" "$a")
      # The same bug again (fork mode): same place in hapsim, or the same message up to numbers.
      key=$(sed -E 's/.*\| at //; s/0x[0-9a-f]+|[-+]?[0-9][0-9.e+-]*|-?nan|-?inf//g' <<< "$what")
      [[ -n ${seen[$key]:-} ]] && continue
      seen[$key]=1
      findings_report+="finding: $what"$'\n'
      findings_report+="input: $a ($(wc -c < "$a") bytes)"$'\n'
      findings_report+="  reproduce: $build/tests/fuzz/fuzz_$t $a"$'\n'
      findings_report+="  keep it:   cp $a tests/fuzz/regressions/$t/<what-it-breaks>"
      findings_report+="  (ctest fuzz_${t}_inputs then runs it in the normal build)"$'\n'
      if (($(wc -c < "$a") <= 2048)); then
        findings_report+="  base64 (for CI logs): $(base64 -w0 "$a")"$'\n'
      fi
    done
    unset seen
  fi
done

echo
echo "fuzz.sh: $(($(date +%s) - start)) s in all (build ${build_s} s); logs in $log_dir"
if ((status != 0)); then
  echo "fuzz.sh: FINDINGS$findings_report" >&2
fi
exit $status
