#!/usr/bin/env bash
# The LCM hub dying and coming back (issue 16, fault matrix): rsd with an `lcm` source on
# tcpq://127.0.0.1 (the hub is lcm-java's TCPService) rectifies a recording played by
# rsd-replay; the hub is killed, rsd says the source was lost and keeps retrying; the hub comes
# back on the same port and the recording is played again: rsd reconnects and rectifies it too.
#   lcm_hub_restart.sh RSD RSD_REPLAY LOG
set -u
rsd=$1 replay=$2 log=$3
. "$(dirname "$0")/../support/rss.sh"
work=$(mktemp -d); server= rsd_pid=
cleanup() {
  [ -n "$rsd_pid" ] && kill -9 "$rsd_pid" 2>/dev/null
  [ -n "$server" ] && kill "$server" 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT
fail() { echo "lcm_hub_restart: $*"; tail -25 "$work/err" 2>/dev/null; exit 1; }
port=$((21000 + $$ % 20000))
start_hub() {
  : >"$work/hub.log"
  java -cp /usr/share/java/lcm.jar lcm.lcm.TCPService "$port" >"$work/hub.log" 2>&1 &
  server=$!
  for _ in $(seq 300); do grep -q "clients" "$work/hub.log" && return 0; kill -0 "$server" 2>/dev/null || break; sleep 0.1; done
  fail "the hub did not start on port $port: $(cat "$work/hub.log")"
}
# rsd is connected once the hub counts a client. At least one, not exactly one: a CI run saw the
# hub count two for 30 s with one lcm_create in rsd (rsd's hub probe, a connection it closes, is
# the likely second under load; under study, docs/reliability.md). What the test asserts is what
# comes out of rsd across the restart, below.
wait_clients() {
  for _ in $(seq 300); do grep -qE " [1-9][0-9]* clients" "$work/hub.log" && return 0; sleep 0.1; done
  fail "the hub never saw a client: $(tail -3 "$work/hub.log")"
}
start_hub
printf 'source:\n  driver: lcm\n  lcm:\n    url: tcpq://127.0.0.1:%s\n    open_timeout_s: 2\n' "$port" >"$work/rsd.yaml"
"$rsd" --config "$work/rsd.yaml" --record "$work/out.lcmlog" --duration 60 --quiet 2>"$work/err" &
rsd_pid=$!
wait_clients 1
sleep 0.5
"$replay" "$log" --lcm-url "tcpq://127.0.0.1:$port" --quiet || fail "the first playing failed"
sleep 1
rss0=$(rss_kb "$rsd_pid")
kill "$server"; wait "$server" 2>/dev/null; server=
sleep 3
kill -0 "$rsd_pid" 2>/dev/null || fail "rsd ended when the hub died"
start_hub
wait_clients 1
sleep 0.5
"$replay" "$log" --lcm-url "tcpq://127.0.0.1:$port" --quiet || fail "the second playing failed"
sleep 1.5
rss1=$(rss_kb "$rsd_pid")
rss_bounded "$rss0" "$rss1" || fail "memory grew from $rss0 kB to $rss1 kB across the hub's restart"
kill -TERM "$rsd_pid"; status=0; wait "$rsd_pid" || status=$?; rsd_pid=
[ "$status" -eq 0 ] || fail "rsd exited $status"
grep -q "camera lost" "$work/err" || fail "the hub's death was not said"
grep -q "reopened" "$work/err" || fail "no reconnection was said"
frames=$("$replay" "$log" --info | sed -n 's/^raw frames: //p')
infos=$("$replay" "$work/out.lcmlog" --info | sed -n 's/^frame infos: \([0-9]*\) .*/\1/p')
[ "${infos:-0}" -ge $((2 * frames - 4)) ] || fail "$infos frames came out of rsd for 2 x $frames played"
echo "OK: 2 x $frames frames played across a hub restart, $infos came out of rsd, RSS $rss0 -> $rss1 kB"
