#!/usr/bin/env bash
# Set up, build, and run the main job: for now a headless FEM run of the reference block
# (scenes/block_small.yaml, 200 implicit steps at 1/60 s) writing CSV, JSON and VTK to out/demo.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
out=out/demo
build/apps/hapsim fem scenes/block_small.yaml --out "$out" --summary "$out/summary.json"
echo
echo "demo: outputs in $out/"
ls -1 "$out"
