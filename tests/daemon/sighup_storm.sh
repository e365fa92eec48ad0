#!/usr/bin/env bash
# SIGHUP storms and SIGTERM under load (issue 16, fault matrix): while rsd runs at a full
# 640x480 at 60 fps, its configuration flips between good variants and broken ones and a SIGHUP
# comes every 20 ms for 4 s. The daemon must stay alive and bounded and answer every reload
# request: a bad file refused by name, a good one applied, and SIGTERM end it with status 0.
#
# Signals arriving while one is handled coalesce, and a slow (sanitizer, loaded) build handles
# only a few of the storm's, reading whichever file is there at that moment: so the storm itself
# asserts only survival and memory; afterwards each request is sent alone and its answer waited
# for (a log line), a bad file and then good variants until one is seen applied. Every wait is
# for an event; its limit only ends a run that hangs.
#   sighup_storm.sh RSD
set -u
rsd=$1
. "$(dirname "$0")/../support/rss.sh"
scale=${RSD_TEST_TIME_SCALE:-1}
work=$(mktemp -d); pid=
trap '[ -n "$pid" ] && kill -9 "$pid" 2>/dev/null; rm -rf "$work"' EXIT
fail() { echo "sighup_storm: $*"; tail -20 "$work/err"; exit 1; }
good() { printf 'source:\n  sim: {width: 640, height: 480, fps: %s}\n' "$1" >"$work/rsd.yaml"; }
bad() { printf 'source:\n  sim: {width: 640, height: 480, fps: -%s}\n' "$1" >"$work/rsd.yaml"; }
count() { grep -c "$1" "$work/err"; }
# Waits (at most 60 s x scale) until PATTERN is in the log N times.
wait_count() {
  local i=0
  until [ "$(count "$1")" -ge "$2" ]; do
    kill -0 "$pid" 2>/dev/null || fail "rsd died waiting for '$1'"
    [ $i -ge $((600 * scale)) ] && fail "no '$1' (x$2) within $((60 * scale)) s"
    sleep 0.1; i=$((i + 1))
  done
}
answers='reload refused\|configuration error\|calibration reloaded\|restarting the pipeline'
refused='reload refused\|configuration error'
restarts='restarting the pipeline'
# One request: SIGHUP, then wait for one more answer than before.
request() {
  local n; n=$(count "$answers")
  kill -HUP "$pid" 2>/dev/null || fail "rsd is not running"
  wait_count "$answers" $((n + 1))
}
good 60
"$rsd" -c "$work/rsd.yaml" --quiet 2>"$work/err" &
pid=$!
wait_count 'rsd: info: sim 640x480' 1
rss0=$(rss_kb "$pid")
for i in $(seq 1 200); do
  case $((i % 4)) in 0) good 60 ;; 1) bad 7 ;; 2) good 50 ;; 3) printf '? [a, b]\n: 1\n' >"$work/rsd.yaml" ;; esac
  kill -HUP "$pid" 2>/dev/null || fail "rsd died during the storm (after $i signals)"
  sleep 0.02
done
storm_answers=$(count "$answers")
# A bad file: refused by name (a pending signal of the storm reads it too, and is refused too).
bad 9; request
[ "$(count "$refused")" -ge 1 ] || fail "the broken file was not refused"
grep -q "must be" "$work/err" || fail "no refusal named the bad value"
# Good variants, each request answered, until one differs from the running file and is applied
# (a file equal to the running one is a calibration reload, applied between two frames).
r0=$(count "$restarts")
for fps in 50 60 50; do
  good "$fps"; request
  [ "$(count "$restarts")" -gt "$r0" ] && break
done
[ "$(count "$restarts")" -gt "$r0" ] || fail "no good configuration was applied"
wait_count 'rsd: info: sim 640x480' $(( $(count "$restarts") + 1 ))  # the restarted pipeline runs
kill -0 "$pid" 2>/dev/null || fail "rsd is not running after the storm"
rss1=$(rss_kb "$pid")
rss_bounded "$rss0" "$rss1" || fail "memory grew from $rss0 kB to $rss1 kB"
# SIGTERM: status 0 within the service unit's TimeoutStopSec (2 s; a guard against a hang).
t0=$(date +%s%N)
kill -TERM "$pid"
status=0; wait "$pid" || status=$?
pid=
ms=$((($(date +%s%N) - t0) / 1000000))
[ "$status" -eq 0 ] || fail "SIGTERM after the storm: status $status"
[ "$ms" -le $((2000 * scale)) ] || fail "SIGTERM took $ms ms"
echo "OK: $storm_answers answers to the storm's 200 signals, $(count "$restarts") restarts, $(count "$refused") refusals, RSS $rss0 -> $rss1 kB, stopped in $ms ms"
