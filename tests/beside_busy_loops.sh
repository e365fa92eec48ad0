#!/usr/bin/env bash
# beside_busy_loops.sh COMMAND [ARG...]: runs COMMAND with two busy loops at nice 19 beside it
# and exits with its status. A laptop, a CI runner among other jobs or a robot's computer is
# never idle: a test that passes only on an idle machine (one that waits for the wall clock
# instead of an event) fails here. The loops take almost nothing from a test at nice 0 (the
# scheduler gives them about 1.5 % each against it), but they take every idle cycle, so that a
# thread at a lower priority (the online calibration's, at nice 10) and any wake-up compete.
#   tests/beside_busy_loops.sh ctest --test-dir build -L e2e --output-on-failure
set -u
[ $# -ge 1 ] || { echo "usage: beside_busy_loops.sh COMMAND [ARG...]" >&2; exit 2; }
loops=()
stop_loops() { [ ${#loops[@]} -gt 0 ] && kill "${loops[@]}" 2>/dev/null; wait "${loops[@]}" 2>/dev/null; loops=(); }
trap stop_loops EXIT
trap 'exit 130' INT TERM
for _ in 1 2; do
  nice -n 19 sh -c 'while :; do :; done' &
  loops+=($!)
done
echo "beside_busy_loops: two busy loops at nice 19 (pids ${loops[*]}) beside: $*"
status=0
"$@" || status=$?
exit $status
