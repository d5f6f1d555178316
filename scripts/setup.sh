#!/usr/bin/env bash
# Installs the Debian packages hapsim needs (skipping those already there; needs root or sudo
# only when something is missing), then configures and builds into build/.
# Usage: scripts/setup.sh [--demo] [extra cmake -D options]
#   --demo  only what scripts/demo.sh runs: the packages `hapsim` needs and the `hapsim` target,
#           without the tests, fuzzers, benchmarks and their tools (issue 25: a newcomer waited
#           10 min 54 s for the first result, 7 min of it building what the demo never runs).
#           A later run without --demo installs and builds the rest into the same build/.
set -euo pipefail
cd "$(dirname "$0")/.."
demo=0
if [ "${1:-}" = "--demo" ]; then
  demo=1
  shift
fi

# Why each package: Eigen (linear algebra), SuiteSparse (CHOLMOD sparse Cholesky), OpenBLAS
# serial (CHOLMOD's supernodal kernels, and the exact compliance's in
# fem/inverse_quadratic_form.cc through libblas-dev's libblas.so; about 2x faster than the
# reference BLAS, single-threaded so benchmarks measure one core), LAPACK (dgetrf for the frame friction solve's Newton steps,
# frame_friction_solver.cc; SuiteSparse already pulls it in), yaml-cpp (scenes), CLI11 (command
# line), GoogleTest and
# Google Benchmark (tests, benchmarks), nlohmann-json (JSON outputs), matplotlib (charts), PyYAML
# (the scene variants of scripts/bench.sh; a Debian package rather than a hand-written YAML
# writer), FCL (collision detection: bounding-volume hierarchy over the body surface, triangle-vs-tool tests),
# LCM (message types, UDP multicast transport between the visual and the haptic process, event
# logs; liblcm-bin has lcm-gen, lcm-logger and lcm-logplayer), libssl-dev (OpenSSL's SHA-256 of
# the files a run reads, recorded in its log), clang and libclang-rt-14-dev (libFuzzer and the
# sanitizer runtimes for scripts/fuzz.sh), OpenCV's viz (VTK), imgcodecs and videoio with libx11
# (`hapsim view` and `hapsim train`: the 3D window, PNG screenshots, AVI videos), xvfb, xdotool
# and x11-utils (headless windows in the tests, driven as a person would; xwininfo), the Gmsh API
# (libgmsh-dev: organ surfaces filled with tets at load, fem/surface_mesher.h), CGAL (libcgal-dev,
# header-only: tests/bench/mesher_comparison.cc measures its Mesh_3 against Gmsh; built with
# -DHAPSIM_BUILD_MESHER_COMPARISON=ON), lld (links the tests in a quarter of GNU ld's time;
# CMakeLists.txt uses it when present).
packages=(
  build-essential cmake pkg-config
  libeigen3-dev libsuitesparse-dev libopenblas0-serial libblas-dev liblapack-dev
  libyaml-cpp-dev libcli11-dev libfcl-dev
  liblcm-dev liblcm-bin libssl-dev
  nlohmann-json3-dev libgmsh-dev
  libopencv-viz-dev libopencv-imgcodecs-dev libopencv-videoio-dev libx11-dev
)
# The tests, fuzzers, benchmarks and charts only.
if [ "$demo" -eq 0 ]; then
  packages+=(libgtest-dev libbenchmark-dev python3 python3-matplotlib python3-yaml
    clang libclang-rt-14-dev xvfb xdotool x11-utils libcgal-dev lld)
fi

missing=()
for package in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" ||
    missing+=("$package")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  sudo_cmd=()
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "setup: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
    sudo_cmd=(sudo)
  fi
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

if [ "$demo" -eq 1 ]; then
  cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DHAPSIM_BUILD_TESTS=OFF \
    -DHAPSIM_BUILD_BENCHMARKS=OFF "$@" >/dev/null
  cmake --build build -j2 --target hapsim
else
  cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DHAPSIM_BUILD_TESTS=ON \
    -DHAPSIM_BUILD_BENCHMARKS=ON "$@" >/dev/null
  cmake --build build -j2
fi
