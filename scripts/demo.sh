#!/usr/bin/env bash
# Set up, build, and run the main job: a two-process run of scenes/block_press.yaml (a cylinder
# pressed into a soft block, slid and lifted off), headless with the scripted device. The visual
# process (`hapsim run`: FEM, contact, linear contact model) spawns the 1 kHz haptic process
# (`hapsim haptic`); they talk over LCM, and every channel is logged. The log is then replayed,
# which checks that it reproduces every device force bit for bit and exports them as CSV.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh --demo  # the packages and the one program this job needs (scripts/test.sh: the rest)
out=out/demo
mkdir -p "$out"
run=(build/apps/hapsim run scenes/block_press.yaml --log "$out/run.lcm"
     --haptic-summary "$out/haptic_summary.json")
# LCM multicasts on this machine only (ttl=0). Without a route for multicast (a machine with no
# network at all) and as root, run in a private network namespace with one on loopback.
if ip route get 239.255.76.67 > /dev/null 2>&1; then
  "${run[@]}"
elif [ "$(id -u)" -eq 0 ] && unshare -n true 2> /dev/null; then
  unshare -n bash -c 'ip link set lo up && ip route add 224.0.0.0/4 dev lo && exec "$@"' _ "${run[@]}"
else
  echo "demo: no multicast route; add one, e.g.: sudo ip route add 224.0.0.0/4 dev lo" >&2
  exit 1
fi
build/apps/hapsim replay "$out/run.lcm" --csv "$out/haptic.csv"
echo
echo "demo: outputs in $out/"
echo "  run.lcm              LCM event log of every channel (lcm-logplayer, lcm-spy)"
echo "  haptic_summary.json  the 1 kHz loop: period error, model latency, forces"
echo "  haptic.csv           every haptic step's device force, tool pose and model in use"
