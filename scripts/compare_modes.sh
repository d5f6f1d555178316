#!/usr/bin/env bash
# Regenerates the accuracy and frame-cost figures of docs/BENCHMARKS.md for issue 3 on
# scenes/block_press.yaml: the reference (everything at 1 kHz, exact compliance), the hybrid (the
# default), linear, lcp and coupling modes at the scene's 33.3 Hz visual rate (30 haptic steps per
# frame) with the warped compliance, and linear with the exact compliance; then device-force errors against the
# reference, the force chart and the frame breakdown against contact count. Takes a few
# minutes (the reference runs 3,000 full frames); not part of ctest. Outputs in out/compare/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
out=out/compare
mkdir -p "$out"
scene=scenes/block_press.yaml
for mode in reference hybrid linear lcp coupling; do
  build/apps/hapsim sim "$scene" --mode "$mode" --out "$out/$mode"
done
build/apps/hapsim sim "$scene" --mode linear --compliance exact --out "$out/linear_exact"
# Debian's interpreter: python3-matplotlib is installed for it, not for any other python3 on PATH.
/usr/bin/python3 scripts/compare_modes.py "$out/errors.json" "$out/forces.png" \
  "$out/reference" "$out/hybrid" "$out/linear" "$out/lcp" "$out/coupling" "$out/linear_exact"
/usr/bin/python3 scripts/plot_frame_breakdown.py "$out/frame_breakdown.png" \
  "linear, warped compliance=$out/linear/frames.csv" \
  "linear, exact compliance=$out/linear_exact/frames.csv"
echo "compare: outputs in $out/"
