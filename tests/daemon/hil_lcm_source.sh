#!/bin/sh
# Hardware in the loop without hardware: a recorded log is published on LCM as a camera would
# (rsd-replay, or lcm-logplayer), and an unmodified rsd with an `lcm` source rectifies it and
# records its outputs. The transport is LCM's TCP queue on 127.0.0.1 (tcpq://, the server is
# lcm-java's lcm.lcm.TCPService): no multicast, nothing leaves the machine.
# Usage: hil_lcm_source.sh RSD RSD_REPLAY LOG WORKDIR [rsd-replay|lcm-logplayer]
# Passes when every recorded frame (at most 2 short) comes out of rsd rectified.
set -eu
rsd=$1 replay=$2 log=$3 dir=$4 player=${5:-rsd-replay}
mkdir -p "$dir"
port=$((20000 + $$ % 20000))
out="$dir/hil-$player.lcmlog"
cfg="$dir/hil-$player.yaml"
rm -f "$out"

frames=$("$replay" "$log" --info | sed -n 's/^raw frames: //p')
[ "$frames" -ge 5 ] || { echo "hil: $log holds only '$frames' raw frames" >&2; exit 1; }

server=
rsd_pid=
cleanup() {
  [ -n "$rsd_pid" ] && kill "$rsd_pid" 2>/dev/null || true
  [ -n "$server" ] && kill "$server" 2>/dev/null || true
}
trap cleanup EXIT
# Start the hub; if its port is taken, try the next one. Java takes a moment to start; the
# server then reports its clients every second.
for attempt in 1 2 3; do
  log_server="$dir/hil-$player-server.log"
  java -cp /usr/share/java/lcm.jar lcm.lcm.TCPService "$port" >"$log_server" 2>&1 &
  server=$!
  i=0
  while ! grep -q "clients" "$log_server" 2>/dev/null && kill -0 "$server" 2>/dev/null && [ $i -lt 300 ]; do
    i=$((i + 1))
    sleep 0.1
  done
  grep -q "clients" "$log_server" && break
  kill "$server" 2>/dev/null || true
  server=
  port=$((port + 1))
done
[ -n "$server" ] || { echo "hil: TCPService did not start" >&2; cat "$log_server" >&2; exit 1; }

printf 'source:\n  driver: lcm\n  lcm:\n    url: tcpq://127.0.0.1:%s\n    open_timeout_s: 5\n' "$port" >"$cfg"
"$rsd" --config "$cfg" --record "$out" --frames "$frames" --duration 30 --quiet &
rsd_pid=$!
# The "camera" starts once rsd has connected (the hub counts it) and subscribed. At least one
# client, not exactly one: under the ASan tree with busy loops beside it the hub once counted 2
# from its first report, waited out rsd's 30 s, and the frames came after rsd had given up.
i=0
until grep -qE " [1-9][0-9]* clients" "$log_server" || [ $i -ge 300 ]; do
  i=$((i + 1))
  sleep 0.1
done
sleep 0.5
if [ "$player" = lcm-logplayer ]; then
  lcm-logplayer --lcm-url "tcpq://127.0.0.1:$port" --regexp '^RSD_(RAW|VELOCITY)$' "$log"
else
  "$replay" "$log" --lcm-url "tcpq://127.0.0.1:$port" --quiet
fi
wait "$rsd_pid"
rsd_pid=
info=$("$replay" "$out" --info)
echo "$info"
infos=$(echo "$info" | sed -n 's/^frame infos: \([0-9]*\) .*/\1/p')
rectified=$(echo "$info" | sed -n 's/^frame infos: .*(rectified \([0-9]*\))/\1/p')
echo "hil ($player): $frames frames published, $infos came out of rsd, $rectified rectified"
[ "$infos" -ge $((frames - 2)) ] && [ "$rectified" -ge $((frames - 2)) ]
