# Sourced by the tests that cross processes over LCM (two_process_test.sh, view_test.sh,
# train_test.sh), right after `set -euo pipefail`:
#
#   source "$(dirname "$0")/local_network.sh" "$0" "$@"
#
# Traffic must stay on this machine. As root, the script is run again inside a private network
# namespace (unshare -n: loopback up, multicast routed on it), where no datagram can leave;
# otherwise it stays here and uses a port unique to this run with ttl=0. Defines: url (the LCM
# URL), work (a fresh folder, on tmpfs when there is one: a log writer stalled by a busy disk
# would drop datagrams; removed at exit with the background jobs stopped) and fail().
if [ -z "${HAPSIM_IN_NETNS:-}" ] && [ "$(id -u)" -eq 0 ] && unshare -n true 2>/dev/null; then
  exec env HAPSIM_IN_NETNS=1 unshare -n bash -c \
    'ip link set lo up && ip route add 224.0.0.0/4 dev lo && exec "$0" "$@"' "$@"
fi
port=$((20000 + $$ % 20000))
url="udpm://239.255.76.67:$port?ttl=0&recv_buf_size=4194304"
work=$(mktemp -d -p /dev/shm 2> /dev/null || mktemp -d)
trap 'kill $(jobs -p) 2> /dev/null || true; rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

# Starts Xvfb on a display of this run's own and exports DISPLAY (view_test, train_test).
start_xvfb() {
  local display=":$((100 + $$ % 400))"
  Xvfb "$display" -screen 0 1280x1024x24 -nolisten tcp > "$work/xvfb.log" 2>&1 &
  export DISPLAY="$display"
  for _ in $(seq 50); do xdpyinfo > /dev/null 2>&1 && return 0; sleep 0.1; done
  fail "Xvfb did not start: $(cat "$work/xvfb.log")"
}
