#!/usr/bin/env bash
# The README's first command shows the product: `rsd` with no configuration runs the built-in
# simulated camera, whose IMU is 2.5 ms off the camera's clock and reads a gyro bias of
# [4, -3, 2] mrad/s (drivers/sim_config.cpp, embedded_default); the online calibration (observe,
# the default) learns both, and the live status line says so. The script waits for the
# convergence (a log line), not for a time: its limit only ends a run that hangs. It runs with
# --until-calibrated, so rsd ends by itself, with status 0, a second after converging.
#   embedded_default.sh RSD
set -u
rsd=$1
# Feature tracking and Ceres fits under AddressSanitizer run ten to twenty times slower: a long
# numerical run, skipped there (docs/reliability.md). The daemon's live runs on the same default
# (daemon_runs_on_simulated_camera, the SIGHUP tests) run its estimator thread under both trees.
case ${RSD_TEST_SANITIZER:-} in *address*) echo "embedded_default: skipped under AddressSanitizer"; exit 77 ;; esac
scale=${RSD_TEST_TIME_SCALE:-1}
work=$(mktemp -d); pid=
trap '[ -n "$pid" ] && kill -9 "$pid" 2>/dev/null; rm -rf "$work"' EXIT
fail() { echo "embedded_default: $*"; tr '\r' '\n' <"$work/err" | tail -20; exit 1; }
"$rsd" --duration $((300 * scale)) --until-calibrated 2>"$work/err" &
pid=$!
i=0
until grep -q "online calibration converged:" "$work/err"; do
  kill -0 "$pid" 2>/dev/null || fail "rsd ended before the online calibration converged"
  [ $i -ge $((2400 * scale)) ] && fail "the online calibration did not converge within $((240 * scale)) s"
  sleep 0.1; i=$((i + 1))
done
# The status line (rewritten in place once a second) shows it too.
i=0
until tr '\r' '\n' <"$work/err" | grep -q "; online converged: offset"; do
  [ $i -ge $((300 * scale)) ] && fail "the status line never said 'online converged'"
  sleep 0.1; i=$((i + 1))
done
status=0; wait "$pid" || status=$?; pid=
[ "$status" -eq 0 ] || fail "rsd exited $status after converging (--until-calibrated)"
line=$(grep -m1 "online calibration converged:" "$work/err")
offset=$(echo "$line" | sed -n 's/.*time offset \([-0-9.]*\) +- .*/\1/p')
bias=$(echo "$line" | sed -n 's/.*gyro bias \[\([-0-9., ]*\)\].*/\1/p')
[ -n "$offset" ] && [ -n "$bias" ] || fail "cannot read the estimate from: $line"
# Truth: 2.5 ms and [0.004, -0.003, 0.002] rad/s; the online calibration's tolerances (0.5 ms,
# 0.002 rad/s on each axis; docs/online-calibration.md).
awk -v o="$offset" -v b="$bias" 'BEGIN {
  n = split(b, v, ", *"); split("0.004 -0.003 0.002", t, " ")
  if (n != 3 || (o - 2.5) ^ 2 > 0.25) exit 1
  for (k = 1; k <= 3; ++k) if ((v[k] - t[k]) ^ 2 > 0.002 ^ 2) exit 1
}' || fail "converged to offset $offset ms, bias [$bias] rad/s; truth 2.5 ms, [0.004, -0.003, 0.002]"
echo "OK: converged to offset $offset ms, bias [$bias] rad/s (truth 2.5 ms, [0.004, -0.003, 0.002]); status: $(tr '\r' '\n' <"$work/err" | grep -m1 -o 'online converged: .*mrad/s')"
