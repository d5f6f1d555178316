#!/usr/bin/env bash
# Regenerates docs/RESULTS.md and every chart in it from scratch (issue 12): the experiments of
# scripts/bench/ (accuracy against closed forms and the reference, with the cost beside it;
# stability maps), one progress line per run, the machine, the date and the wall time.
# Usage: scripts/bench.sh [--quick] [--only NAME,...]
#   --quick   the smallest sweeps, a few minutes, outputs in out/results_quick/ (docs/ untouched;
#             ctest runs this and checks the JSON)
#   --only    some experiments (scripts/bench/run.py --help lists them), outputs in
#             out/results_part/ (or out/results_quick_part/ with --quick)
# Full run: outputs in out/results/, then docs/RESULTS.md and docs/results/*.png.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
quick=()
out=out/results
install=(--results-md docs/RESULTS.md)
passthrough=()
for arg in "$@"; do
  case $arg in
    --quick) quick=(--quick); out=out/results_quick; install=() ;;
    *) passthrough+=("$arg") ;;
  esac
done
# --only runs a part: its page goes to out/results_part/, never over docs/RESULTS.md.
if [[ " ${passthrough[*]-} " == *" --only"* ]]; then install=(); out=${out/results/results_part}; fi
# Debian's interpreter: python3-matplotlib and python3-yaml are installed for it.
exec /usr/bin/python3 scripts/bench/run.py --hapsim build/apps/hapsim --out "$out" \
  "${quick[@]}" "${install[@]}" "${passthrough[@]}"
