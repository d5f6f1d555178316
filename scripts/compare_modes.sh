#!/usr/bin/env bash
# Regenerates the accuracy figures of docs/BENCHMARKS.md for issue 3: block_press in the
# reference mode (everything at 1 kHz) and in the linear, lcp and coupling modes at 30 Hz visual
# rate (33.3 Hz: 30 haptic steps per frame), then device-force errors against the reference and
# a chart. Takes a few minutes (the reference runs 3,000 full frames); not part of ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
out=out/compare
mkdir -p "$out"
for mode in reference linear lcp coupling; do
  build/apps/hapsim sim scenes/block_press.yaml --mode "$mode" --out "$out/$mode"
done
/usr/bin/python3 scripts/compare_modes.py "$out/errors.json" "$out/forces.png" \
  "$out/reference" "$out/linear" "$out/lcp" "$out/coupling"
echo "compare: outputs in $out/"
