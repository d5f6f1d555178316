#!/usr/bin/env bash
# Regenerates the pictures and figures of docs/SCENES.md: each scene with a tool runs as two
# processes (`hapsim run`, its scripted device) for a few seconds, and `hapsim view` draws its log at
# the moment the scene's press is deepest; `hapsim inspect` gives its objects, DOFs and frame cost.
# Headless: under Xvfb (xvfb-run). LCM stays on this machine: a private network namespace when
# root, else a port of its own with ttl=0.
#
#   scripts/scene_screenshots.sh [SCENE ...]   # writes docs/scenes/<scene>.png and .json (all, or
#                                              # only the scenes named)
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -z "${HAPSIM_IN_NETNS:-}" ] && [ "$(id -u)" -eq 0 ] && unshare -n true 2>/dev/null; then
  exec env HAPSIM_IN_NETNS=1 unshare -n bash -c \
    'ip link set lo up && ip route add 224.0.0.0/4 dev lo && exec "$0" "$@"' "$0" "$@"
fi
hapsim=build/apps/hapsim
[ -x "$hapsim" ] || scripts/setup.sh
url="udpm://239.255.76.67:$((20000 + $$ % 20000))?ttl=0&recv_buf_size=4194304"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p docs/scenes
# scene, seconds to run, time of the picture (mid-press), colours from the shape at (s)
for entry in "block_press 1.6 1.5 0" "liver_palpation 3.6 3.5 1.0" "probe_on_tray 1.6 1.5 0" \
  "polyp 3.2 3.0 0.5" "pick_and_place 5.6 5.5 0" "peg_in_hole 2.9 2.8 0" "probe 4.9 4.8 0" \
  "two_organs 5.6 5.5 1.0" "retraction 2.5 2.4 0.7" "organs 2.5 2.4 0.6" "drop 7.8 7.7 0"; do
  read -r scene duration at settle <<< "$entry"
  if [ $# -gt 0 ] && [[ " $* " != *" $scene "* ]]; then continue; fi
  echo "scene_screenshots: $scene"
  "$hapsim" inspect "scenes/$scene.yaml" --json "docs/scenes/$scene.json" > /dev/null
  "$hapsim" run "scenes/$scene.yaml" --lcm-url "$url" --duration "$duration" --log "$work/$scene.lcm" \
    > "$work/$scene.out" 2>&1 || { cat "$work/$scene.out"; exit 1; }
  xvfb-run -a -s "-screen 0 1280x1024x24" "$hapsim" view "$work/$scene.lcm" \
    --screenshot "docs/scenes/$scene.png" --at "$at" --size 800x600 --displacement-from "$settle" \
    | tail -1
done
