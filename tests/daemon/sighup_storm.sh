#!/usr/bin/env bash
# SIGHUP storms and SIGTERM under load (issue 16, fault matrix): while rsd runs at a full
# 640x480 at 60 fps, its configuration flips between good variants and broken ones and a SIGHUP
# comes every 20 ms for 4 s. The daemon must keep running (bad files refused by name, good ones
# applied), its memory stay bounded, and SIGTERM end it with status 0 within 1 s.
#   sighup_storm.sh RSD
set -u
rsd=$1
. "$(dirname "$0")/../support/rss.sh"
work=$(mktemp -d); pid=
trap '[ -n "$pid" ] && kill -9 "$pid" 2>/dev/null; rm -rf "$work"' EXIT
fail() { echo "sighup_storm: $*"; tail -20 "$work/err"; exit 1; }
good() { printf 'source:\n  sim: {width: 640, height: 480, fps: %s}\n' "$1" >"$work/rsd.yaml"; }
bad() { printf 'source:\n  sim: {width: 640, height: 480, fps: -%s}\n' "$1" >"$work/rsd.yaml"; }
good 60
"$rsd" -c "$work/rsd.yaml" --quiet 2>"$work/err" &
pid=$!
sleep 1.5
rss0=$(rss_kb "$pid")
for i in $(seq 1 200); do
  case $((i % 4)) in 0) good 60 ;; 1) bad 7 ;; 2) good 50 ;; 3) printf '? [a, b]\n: 1\n' >"$work/rsd.yaml" ;; esac
  kill -HUP "$pid" 2>/dev/null || fail "rsd died during the storm (after $i signals)"
  sleep 0.02
done
# One broken file after the storm, answered before going on: a slow (sanitizer) build restarts
# only a few times during the storm and may happen to read good files only.
bad 9; kill -HUP "$pid"
i=0
until grep -q "configuration error\|reload refused\|must be" "$work/err" || [ $i -ge $((100 * ${RSD_TEST_TIME_SCALE:-1})) ]; do
  sleep 0.1; i=$((i + 1))
done
good 60; kill -HUP "$pid"; sleep 1.5
kill -0 "$pid" 2>/dev/null || fail "rsd is not running after the storm"
rss1=$(rss_kb "$pid")
rss_bounded "$rss0" "$rss1" || fail "memory grew from $rss0 kB to $rss1 kB"
t0=$(date +%s%N)
kill -TERM "$pid"
status=0; wait "$pid" || status=$?
pid=
ms=$((($(date +%s%N) - t0) / 1000000))
[ "$status" -eq 0 ] || fail "SIGTERM after the storm: status $status"
[ "$ms" -le $((1000 * ${RSD_TEST_TIME_SCALE:-1})) ] || fail "SIGTERM took $ms ms"
grep -q "configuration error\|reload refused\|must be" "$work/err" || fail "no bad configuration was refused by name"
grep -q "configuration reloaded: restarting the pipeline" "$work/err" || fail "no good configuration was applied"
echo "OK: $(grep -c 'restarting the pipeline' "$work/err") restarts, $(grep -c 'refused\|configuration error' "$work/err") refusals, RSS $rss0 -> $rss1 kB, stopped in $ms ms"
