#!/usr/bin/env bash
# Regenerates every FEM figure in docs/BENCHMARKS.md: `hapsim fem --bench` on the three
# reference blocks (200 steps from rest, every solver), the Google Benchmark stage timings,
# and the chart. Takes a few minutes; not part of ctest. Outputs go to out/bench/.
set -euo pipefail
cd "$(dirname "$0")/.."
# One core, as issue 13's targets are stated (BLAS is openblas-serial). Debian's CHOLMOD is built
# with OpenMP and asks for 4 threads in its factorisations by a num_threads clause, which
# OMP_NUM_THREADS does not override; OMP_THREAD_LIMIT does. hapsim itself keeps CHOLMOD on the
# calling thread since 2026-11-26 (fem/cholmod_factor.cc); the limit holds older builds to it too.
export OMP_THREAD_LIMIT=1
scripts/setup.sh
out=out/bench
mkdir -p "$out"
build/apps/hapsim fem --bench scenes/block_tiny.yaml scenes/block_small.yaml scenes/block_large.yaml \
  --out "$out" | tee "$out/fem_bench.txt"
build/tests/fem_step_benchmark --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
  --benchmark_out="$out/fem_step_benchmark.json" --benchmark_out_format=json | tee "$out/fem_step_benchmark.txt"
# Debian's interpreter: python3-matplotlib is installed for it, not for any other python3 on PATH.
/usr/bin/python3 scripts/plot_fem_bench.py "$out/fem_bench.json" "$out/fem_bench.png"
echo "bench: outputs in $out/"
