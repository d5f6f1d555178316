#!/usr/bin/env bash
# End-to-end checks of `hapsim fem` (run by ctest from the repository root):
# a good scene writes its three outputs with one CSV row per step and a summary whose counts
# match the mesh formulas; bad input exits 2 naming file, line and key, and writes nothing;
# an explicit run above its stability limit exits 1 and writes nothing.
set -euo pipefail
hapsim="$1"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

# A good run: block_tiny, 12 steps.
"$hapsim" fem scenes/block_tiny.yaml --steps 12 --out "$work/good" > "$work/good.log"
for f in steps.csv summary.json final_mesh.vtk; do [ -s "$work/good/$f" ] || fail "missing $f"; done
[ "$(wc -l < "$work/good/steps.csv")" -eq 13 ] || fail "steps.csv should have a header and 12 rows"
/usr/bin/python3 - "$work/good/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
# 8 x 8 x 3 cells: 9*9*4 nodes, 5*8*8*3 tets, 81 bottom nodes fixed (independent of the code).
assert s["num_nodes"] == 324 and s["num_tets"] == 960 and s["num_dofs"] == 972, s
assert s["num_fixed_nodes"] == 81 and s["num_steps"] == 12, s
assert s["probes"][0]["name"] == "top_center"
assert s["probes"][0]["final_displacement_m"][2] < 0.0, "gravity must push the top down"
PY
grep -q "^POINTS 324 " "$work/good/final_mesh.vtk" || fail "VTK should hold 324 points"
ls "$work/good" | grep -q tmp && fail "temporary files left behind"

# Bad input: exit 2, message names file, line and key, nothing written.
sed 's/poisson_ratio: 0.45/poisson_ratio: 0.5/' scenes/block_tiny.yaml > "$work/bad.yaml"
set +e
"$hapsim" fem "$work/bad.yaml" --out "$work/bad_out" 2> "$work/bad.err"
status=$?
set -e
[ "$status" -eq 2 ] || fail "bad scene should exit 2, got $status"
grep -q "bad.yaml:15: key 'body.material.poisson_ratio'" "$work/bad.err" || fail "message: $(cat "$work/bad.err")"
[ ! -e "$work/bad_out" ] || fail "bad scene must write nothing"

# Explicit Euler at 1/60 s is far above its stability limit: exit 1, nothing written.
sed 's/integrator: implicit/integrator: explicit/' scenes/block_tiny.yaml > "$work/explicit.yaml"
set +e
"$hapsim" fem "$work/explicit.yaml" --out "$work/explicit_out" > /dev/null 2> "$work/explicit.err"
status=$?
set -e
[ "$status" -eq 1 ] || fail "diverging run should exit 1, got $status"
grep -q "diverged at step" "$work/explicit.err" || fail "message: $(cat "$work/explicit.err")"
[ ! -e "$work/explicit_out" ] || fail "diverged run must write nothing"
# `fem` refuses SCENE with exit 2 and a message matching PATTERN, writing nothing.
expect_refused() {  # SCENE NAME PATTERN
  local scene=$1 name=$2 pattern=$3 status
  set +e
  "$hapsim" fem "$scene" --out "$work/${name}_out" > /dev/null 2> "$work/$name.err"
  status=$?
  set -e
  [ "$status" -eq 2 ] || fail "$name: should exit 2, got $status"
  grep -q "$pattern" "$work/$name.err" || fail "$name: message: $(cat "$work/$name.err")"
  [ ! -e "$work/${name}_out" ] || fail "$name: a refused scene must write nothing"
}
# A scene with rigid objects (the liver on its tray): `fem` would drop the organ through the
# tray, so it refuses, naming the objects' line.
expect_refused scenes/liver_palpation.yaml rigid "liver_palpation.yaml:[0-9]*: key 'objects'"
# Two deformable objects: `fem` steps one, so it refuses, naming the second one's line.
cat > "$work/two.yaml" <<'YAML'
name: two
time: {dt_s: 0.01, num_steps: 2}
objects:
  - name: a
    deformable:
      mesh: {box: {min_m: [0, 0, 0], max_m: [0.01, 0.01, 0.01], cells: [1, 1, 1]}}
      material: {youngs_modulus_Pa: 5000, poisson_ratio: 0.3, density_kg_m3: 1000}
  - name: b
    deformable:
      mesh: {box: {min_m: [0.02, 0, 0], max_m: [0.03, 0.01, 0.01], cells: [1, 1, 1]}}
      material: {youngs_modulus_Pa: 5000, poisson_ratio: 0.3, density_kg_m3: 1000}
YAML
expect_refused "$work/two.yaml" two "two.yaml:9: key 'objects'.*steps one deformable object"
echo "fem_command_test: all checks passed"
