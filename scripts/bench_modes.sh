#!/usr/bin/env bash
# Regenerates the haptic-mode comparison of docs/BENCHMARKS.md (issue 11): every haptic mode of
# `hapsim sim` on scenes/block_press.yaml, scenes/probe.yaml and scenes/peg_in_hole.yaml against
# the reference (everything at 1 kHz, exact compliance): device-force error, the haptic step's
# median cost, the force charts. The reference of block_press runs 3,000 full frames: about two
# minutes in all; not part of ctest. Outputs in out/bench_modes/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
out=out/bench_modes
mkdir -p "$out"
# scene:modes (the godobject mode needs a point tool: probe only; lcp: normal rows, any scene)
runs=("block_press:reference hybrid linear lcp coupling penalty material impact"
      "probe:reference hybrid linear lcp coupling penalty material impact godobject"
      "peg_in_hole:reference hybrid linear lcp coupling penalty material impact")
for entry in "${runs[@]}"; do
  scene=${entry%%:*}
  read -r -a modes <<< "${entry#*:}"
  dirs=()
  for mode in "${modes[@]}"; do
    echo "bench_modes: $scene $mode"
    build/apps/hapsim sim "scenes/$scene.yaml" --mode "$mode" --out "$out/$scene/$mode" > /dev/null
    [[ $mode == reference ]] || dirs+=("$out/$scene/$mode")
  done
  # Debian's interpreter: python3-matplotlib is installed for it, not for any other python3.
  /usr/bin/python3 scripts/compare_modes.py "$out/$scene/errors.json" "$out/$scene/forces.png" \
    "$out/$scene/reference" "${dirs[@]}" > /dev/null
done
/usr/bin/python3 scripts/summarize_modes.py "$out" "$out/haptic_modes.png" block_press probe peg_in_hole |
  tee "$out/table.md"
cp "$out/haptic_modes.png" docs/haptic_modes.png   # the chart of docs/BENCHMARKS.md
echo "bench_modes: outputs in $out/"
