#!/bin/sh
# realtime_unprivileged.sh RSD: `rsd --realtime` without the privileges the service unit grants
# (as nobody, no capabilities, RLIMIT_RTPRIO 0, RLIMIT_MEMLOCK 64 KiB) says once that the capture
# thread stays at normal priority and memory pageable, and runs on: frames still come out and
# it exits 0. Needs root to drop them (status 77, skipped, otherwise).
set -eu
[ "$(id -u)" -eq 0 ] || { echo "not root: cannot drop privileges for the test"; exit 77; }
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cp "$1" "$work/rsd" && chmod 755 "$work" "$work/rsd"
setpriv --reuid=65534 --regid=65534 --clear-groups --inh-caps=-all --bounding-set=-all \
  sh -c "ulimit -r 0; ulimit -l 64; cd /; LCM_DEFAULT_URL=memq:// '$work/rsd' --realtime --frames 10" >"$work/out" 2>&1 ||
  { cat "$work/out"; echo "rsd --realtime failed unprivileged"; exit 1; }
cat "$work/out"
[ "$(grep -c 'SCHED_FIFO 50 is not permitted' "$work/out")" -eq 1 ] || { echo "no single SCHED_FIFO warning"; exit 1; }
# Under a sanitizer (tests/sanitizers/run.sh) mlockall is a no-op that reports success: no warning.
if [ -n "${RSD_TEST_SANITIZER:-}" ]; then
  echo "under $RSD_TEST_SANITIZER: mlockall locks nothing and says nothing, not checked"
else
  [ "$(grep -c 'memory stays pageable' "$work/out")" -eq 1 ] || { echo "no single mlockall warning"; exit 1; }
fi
grep -Eq 'stopping: in [0-9]+ .* out (1[0-9]|[2-9][0-9])' "$work/out" || { echo "frames did not come out"; exit 1; }
echo "OK"
