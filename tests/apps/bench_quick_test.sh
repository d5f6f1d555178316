#!/usr/bin/env bash
# `scripts/bench.sh --quick` as ctest runs it: every experiment of scripts/bench/ on its smallest
# sweep (about a minute), then scripts/bench/check_quick.py on its JSON (each check against a value
# the bench did not make: closed forms, 2/omega_max, the reference). Also: the page and every
# chart it names exist, and a bad --only exits non-zero naming the experiment.
# Under a sanitizer (HAPSIM_SANITIZED) it is skipped (77): minutes of FEM become an hour, and
# every code path it runs is run by the unit tests there.
set -euo pipefail
hapsim="$1"
if [ -n "${HAPSIM_SANITIZED:-}" ]; then echo "skipped under a sanitizer"; exit 77; fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

/usr/bin/python3 scripts/bench/run.py --hapsim "$hapsim" --out "$work/bench" --quick
/usr/bin/python3 scripts/bench/check_quick.py "$work/bench/results.json"
[ -s "$work/bench/RESULTS.md" ] || fail "no RESULTS.md"
grep -o '](\./[^)]*\.png)' "$work/bench/RESULTS.md" | sed 's/](\.\///; s/)$//' | sort -u > "$work/figures"
[ -s "$work/figures" ] || fail "RESULTS.md names no chart"
while read -r png; do
  [ "$(head -c 4 "$work/bench/$png" | od -An -c | tr -d ' ')" = "211PNG" ] ||
    fail "RESULTS.md names $png, which is not a PNG"
done < "$work/figures"
leftover=$(find "$work/bench" -name '*.tmp*')
[ -z "$leftover" ] || fail "temporary files were left behind: $leftover"

if /usr/bin/python3 scripts/bench/run.py --hapsim "$hapsim" --out "$work/bad" --quick \
    --only no_such_experiment 2> "$work/bad.err"; then
  fail "an unknown --only was accepted"
fi
grep -q "no_such_experiment" "$work/bad.err" || fail "the error does not name the experiment"
echo "bench_quick_test: ok"
