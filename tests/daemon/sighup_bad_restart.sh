#!/bin/sh
# Issue 38, defect 6: a changed configuration that passes every check and still fails to start
# (here a replay of a file that is not an LCM log) ended a running daemon over SIGHUP. It now
# restarts with the configuration that ran, says so, and goes on publishing until SIGTERM.
#   sighup_bad_restart.sh RSD WORKDIR
rsd=$1; dir=$2
rm -rf "$dir" && mkdir -p "$dir" && cd "$dir" || exit 1
printf 'source:\n  driver: sim\n  sim: {width: 160, height: 120, fps: 30}\n' > rsd.yaml
printf 'not an LCM log\n' > broken.lcmlog
scale=${RSD_TEST_TIME_SCALE:-1}
count() { grep -c "$1" out.txt; }
said() {  # said TEXT [N]: wait up to 10 s (times the scale) for the N-th line with TEXT
  i=0
  while [ $i -lt $((100 * scale)) ]; do
    [ "$(count "$1")" -ge "${2:-1}" ] && return 0
    kill -0 $pid 2>/dev/null || return 1
    sleep 0.1; i=$((i + 1))
  done
  return 1
}
fail() { cat out.txt; echo "sighup_bad_restart: $1"; kill -9 $pid 2>/dev/null; exit 1; }
"$rsd" -c rsd.yaml > out.txt 2>&1 &
pid=$!
said 'rsd: info: sim 160x120' || fail "no start-up line"
printf 'source:\n  driver: replay\n  replay: {file: broken.lcmlog}\n' > rsd.yaml
"$rsd" --check-config -c rsd.yaml > check.txt 2>&1 || { cat check.txt; fail "the new configuration should pass --check-config"; }
kill -HUP $pid
said 'reload refused: the new configuration failed to start' || fail "the failed restart was not said"
said 'restarting with the one that ran' || fail "no way back to the running configuration"
said 'rsd: info: sim 160x120' 2 || fail "the configuration that ran did not start again"
kill -0 $pid 2>/dev/null || fail "the daemon ended"
kill -TERM $pid
wait $pid; rc=$?
[ $rc -eq 0 ] || fail "rsd exited with $rc after SIGTERM"
echo "sighup_bad_restart: ok"
