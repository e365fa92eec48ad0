#!/usr/bin/env bash
# record_disk_full.sh RSD RSD_REPLAY: a recording that runs out of room (a file size limit of
# 2 MB stands for a full disk) fails its writes, says so once with the reason, and the run goes
# on to its end with status 0; what was written reads back.
set -eu
rsd=$1 replay=$2
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
fail() { echo "record_disk_full: $*"; cat "$work/err"; exit 1; }
status=0
(ulimit -f 2048; exec "$rsd" --frames 45 --quiet --record "$work/run.lcmlog") 2>"$work/err" || status=$?
[ "$status" -eq 0 ] || fail "exited $status, not 0"
grep -Eq "recording to .*run\.lcmlog: [0-9]+ events not written \(File too large\); the run goes on without them" "$work/err" ||
  fail "no error line for the failing recording"
[ "$(grep -c 'events not written' "$work/err")" -le 2 ] || fail "the failure said more than at each tenfold"
size=$(stat -c %s "$work/run.lcmlog")
[ "$size" -le $((2048 * 1024)) ] || fail "the recording is $size bytes, beyond the limit"
"$replay" "$work/run.lcmlog" --info >"$work/info" 2>&1 || fail "what was recorded does not read back: $(cat "$work/info")"
grep -Eq "^raw frames: [1-9]" "$work/info" || fail "no frame in the recording: $(cat "$work/info")"
echo "OK: $(grep -c . "$work/err") log lines, recording $size bytes, $(grep '^raw frames' "$work/info")"
