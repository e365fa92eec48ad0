#!/bin/sh
# run.sh KIND SOURCE_DIR BUILD_DIR [CMAKE_ARG...]: configure, build and test one sanitizer tree
# beside the normal build (docs/reliability.md, "Sanitizers").
#   KIND address,undefined  every target; the whole suite runs under ASan, LeakSanitizer and UBSan,
#                           then each parser's fuzz target for 6 s (the fuzz pass; clang)
#   KIND thread             the threaded targets; their tests run under ThreadSanitizer
# Suppressions for third-party libraries live beside this script, each with its reason. Any
# report the suppressions do not cover fails the test that caused it: ASan, LSan and UBSan end
# the process with an error status, TSan with status 66.
set -eu
kind=$1 src=$2 build=$3
shift 3
here=$(cd "$(dirname "$0")" && pwd)
jobs=$(nproc)
# Tests at a time: a third of the ASan tree's tests spend their time waiting (a daemon's
# restart, the fake GigE camera's frames, a watchdog: about as long there as in the normal tree,
# 200 of its 890 test-seconds), so it runs one more test than there are cores. The TSan tree's
# are threads racing for the cores: one per core.
test_jobs=$jobs
# The shell tests widen their time limits by this factor (tests/support/sanitizer.hpp says the
# same to the C++ tests).
export RSD_TEST_TIME_SCALE=10
# And which sanitizer runs, for the checks that have nothing to check under one.
export RSD_TEST_SANITIZER=$kind

case $kind in
  address,undefined)
    # detect_leaks: LeakSanitizer at every exit; the tools' man pages (help2man runs them at
    # build time) are built under the same options.
    export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:strict_string_checks=1:detect_stack_use_after_return=0:check_initialization_order=1"
    export LSAN_OPTIONS="suppressions=$here/lsan.supp:print_suppressions=0"
    export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:suppressions=$here/ubsan.supp"
    targets=all
    tests=""
    test_jobs=$((jobs + 1))
    ;;
  thread)
    export TSAN_OPTIONS="suppressions=$here/tsan.supp:print_suppressions=0:exitcode=66:second_deadlock_stack=1"
    # The tests with threads of their own (capture, publish, record, velocity, reload, replay)
    # and the daemon's live runs; the single-threaded maths gains nothing from TSan.
    # (The test executables hold their concepts' other tests too: the pattern below picks.)
    targets="test_daemon_pipeline test_daemon_inputs test_daemon_service test_drivers rsd rsd-replay"
    tests="^(DropOldestQueue|VelocityBuffer|Pipeline|WorkerPool|VelocityInput|ServiceReconnect|SourceWatch|ServiceHealth|ServiceReload|Replay|LcmSource|RecordingReplaySource)[A-Za-z]*\.|^daemon_(runs_on_simulated_camera|sighup_storm|sighup_calibration|record_sim|replay_fast)$"
    ;;
  *)
    echo "run.sh: KIND must be address,undefined or thread, not '$kind'" >&2
    exit 2
    ;;
esac

mkdir -p "$(dirname "$build")"
generator=""
command -v ninja >/dev/null 2>&1 && generator="-G Ninja"
[ -f "$build/CMakeCache.txt" ] || generator_arg=$generator
# shellcheck disable=SC2086  # generator and targets are word lists on purpose
cmake -S "$src" -B "$build" ${generator_arg:-} -DCMAKE_BUILD_TYPE=None -DRSD_SANITIZE="$kind" "$@" >"$build.configure.log" 2>&1 ||
  { cat "$build.configure.log" >&2; exit 1; }
start=$(date +%s)
# shellcheck disable=SC2086
cmake --build "$build" -j"$jobs" --target $targets >"$build.build.log" 2>&1 ||
  { tail -n 60 "$build.build.log" >&2; exit 1; }
echo "run.sh: $kind tree built in $(( $(date +%s) - start )) s"
# ctest starts the longest tests first when it knows their times (its cost data), so that no
# long test is left for the end beside an idle core; a fresh tree has none, so it starts from the
# times kept in costs/ (seconds, from a clean clone's run). The order only: a test not listed
# there runs after the listed ones, and every test runs.
history=$build/Testing/Temporary/CTestCostData.txt
if [ ! -f "$history" ]; then
  mkdir -p "$(dirname "$history")"
  { cat "$here/costs/$(echo "$kind" | tr , -).txt"; echo ---; } >"$history"
fi
start=$(date +%s)
if [ -n "$tests" ]; then
  ctest --test-dir "$build" -j"$test_jobs" --output-on-failure -R "$tests"
else
  ctest --test-dir "$build" -j"$test_jobs" --output-on-failure
fi
echo "run.sh: $kind tests ran in $(( $(date +%s) - start )) s"
# The complete suite's fuzz pass: the ASan+UBSan tree built by clang holds the fuzz targets as
# libFuzzer binaries (tests/fuzz/CMakeLists.txt), each fuzzed for 6 s from its corpus under this
# tree's sanitizer options; a finding fails this test and is kept in the corpus.
if [ "$kind" = address,undefined ]; then
  if [ -x "$build/tests/fuzz/fuzz_config" ]; then
    RSD_FUZZ_BUILD=$build bash "$src/tests/fuzz/run.sh" 0.1
  else
    echo "run.sh: no fuzz pass: this tree was not built by clang (no libFuzzer binaries)"
  fi
fi
