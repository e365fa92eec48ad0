#!/usr/bin/env bash
# record_disk_full.sh RSD RSD_REPLAY: a recording that runs out of room (a file size limit of
# 2 MB stands for a full disk) fails its writes, says so once with the reason, and the run goes
# on to its end with status 0; what was written reads back.
set -eu
rsd=$1 replay=$2
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
fail() { echo "record_disk_full: $*"; cat "$work/err"; exit 1; }
. "$(dirname "$0")/../support/rss.sh"
# Five seconds at 30 fps: the limit is reached within the first second; memory is read once the
# writes fail and again at the end (failed events must not pile up anywhere).
(ulimit -f 2048; exec "$rsd" --duration 5 --quiet --record "$work/run.lcmlog") 2>"$work/err" &
pid=$!
sleep 2; rss0=$(rss_kb "$pid")
sleep 2.5; rss1=$(rss_kb "$pid")
status=0; wait "$pid" || status=$?
[ "$status" -eq 0 ] || fail "exited $status, not 0"
grep -Eq "recording to .*run\.lcmlog: [0-9]+ events not written \(File too large\); the run goes on without them" "$work/err" ||
  fail "no error line for the failing recording"
[ "$(grep -c "events not written" "$work/err")" -le 4 ] || fail "the failure said more than at each tenfold"
size=$(stat -c %s "$work/run.lcmlog")
[ "$size" -le $((2048 * 1024)) ] || fail "the recording is $size bytes, beyond the limit"
rss_bounded "$rss0" "$rss1" || fail "memory grew from $rss0 kB to $rss1 kB while writes failed"
"$replay" "$work/run.lcmlog" --info >"$work/info" 2>&1 || fail "what was recorded does not read back: $(cat "$work/info")"
grep -Eq "^raw frames: [1-9]" "$work/info" || fail "no frame in the recording: $(cat "$work/info")"
echo "OK: $(grep -c . "$work/err") log lines, recording $size bytes, $(grep '^raw frames' "$work/info"), RSS $rss0 -> $rss1 kB"
