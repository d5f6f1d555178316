#!/usr/bin/env bash
# What a collision surface embedded in the tets costs and buys (docs/SCENES.md, "Surfaces carried
# by the tets"): liver_palpation's scripted palpation (`hapsim sim`, the scene's hybrid mode) with
# the liver meshed at 12 and 8 mm, touched on the tets' own boundary or on liver.obj (4,514
# points) as `collision` surface, against the liver meshed at 5 mm (its boundary) as reference;
# and the 12 mm pair against their own 1 kHz runs (`--mode reference`). Prints a Markdown table:
# frame and stage medians, most contacts, peak device force, RMS device-force difference.
#
#   scripts/bench_collision_surface.sh [OUT]   (default out/bench_collision_surface; ~4 min)
set -euo pipefail
cd "$(dirname "$0")/.."
hapsim=build/apps/hapsim
[ -x "$hapsim" ] || scripts/setup.sh
out=${1:-out/bench_collision_surface}
mkdir -p "$out"
surface="$PWD/scenes/meshes/liver.obj"
# name, cell size, collision surface (yes/no)
variants="h12:0.012:no h12_surface:0.012:yes h8:0.008:no h8_surface:0.008:yes h5:0.005:no"
for entry in $variants; do
  IFS=: read -r name h collision <<< "$entry"
  scene="$out/$name.yaml"
  sed "s|meshes/liver.obj|$surface|; s|cell_size_m: 0.008 |cell_size_m: $h |" \
    scenes/liver_palpation.yaml > "$scene"
  grep -q "cell_size_m: $h " "$scene" || { echo "cannot set the cell size in $scene" >&2; exit 1; }
  if [ "$collision" = yes ]; then
    sed -i "s|^      material:|      collision: {file: $surface}\n      material:|" "$scene"
  fi
  echo "bench_collision_surface: $name" >&2
  "$hapsim" sim "$scene" --out "$out/$name" > /dev/null
done
for name in h12 h12_surface; do
  echo "bench_collision_surface: $name --mode reference" >&2
  "$hapsim" sim "$out/$name.yaml" --mode reference --out "$out/${name}_reference" > /dev/null
done
/usr/bin/python3 - "$out" <<'PY'
import csv, math, statistics, sys
out = sys.argv[1]
rows = lambda run, name: list(csv.DictReader(open(f"{out}/{run}/{name}.csv")))
force = lambda run: [[float(r[k]) for k in ("force_x_N", "force_y_N", "force_z_N")]
                     for r in rows(run, "haptic")]
def rms(a, b):
    n = min(len(a), len(b))
    return math.sqrt(sum(sum((x - y) ** 2 for x, y in zip(a[i], b[i])) for i in range(n)) / n)
reference = force("h5")
print("| run | frame | detection | response | max contacts | peak force | RMS vs h5 |")
print("|---|---|---|---|---|---|---|")
for run in ("h12", "h12_surface", "h8", "h8_surface", "h5"):
    frames = rows(run, "frames")
    median = lambda key: statistics.median(float(f[key]) for f in frames)
    peak = max(math.hypot(*f) for f in force(run))
    print(f"| {run} | {median('total_ms'):.2f} ms | {median('detection_ms'):.2f} ms | "
          f"{median('response_ms'):.2f} ms | {max(int(f['contacts']) for f in frames)} | "
          f"{peak:.3f} N | {rms(force(run), reference):.3f} N |")
print(f"\nh12_surface vs h12: {rms(force('h12_surface'), force('h12')):.3f} N RMS; each against its "
      f"own --mode reference: {rms(force('h12'), force('h12_reference')):.3f} N (boundary), "
      f"{rms(force('h12_surface'), force('h12_surface_reference')):.3f} N (liver.obj)")
PY
