#!/usr/bin/env bash
# tests/complete.sh [BUILD]: the complete suite, after the README's quick test command has built
# BUILD (default: build) and run its unit, cli and e2e tests. It runs what that command leaves
# out, the CTests labelled `slow`: the ASan+UBSan and TSan trees (which run the unit and e2e
# tests again, instrumented; the first then fuzzes each parser for 6 s), the arm64 cross build
# under qemu, the long closed-loop and online-calibration runs. All of it beside two busy loops
# at nice 19 (beside_busy_loops.sh), as a loaded machine would run it. .ci/run runs it; docs/reliability.md has its times.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=${1:-build}
[ -f "$build/CTestTestfile.cmake" ] || { echo "complete.sh: $build is not a configured build (run the README's test command first)" >&2; exit 2; }
start=$(date +%s)
# The benchmarks, which the quick build leaves out (tests/daemon/CMakeLists.txt): compiled here
# so that CI still sees them build.
cmake --build "$build" --target bench_rs_rectifier bench_pipeline_latency bench_diagnosis
"$here/beside_busy_loops.sh" ctest --test-dir "$build" -j"$(nproc)" --output-on-failure -L slow
echo "complete.sh: the complete suite passed in $(( $(date +%s) - start )) s"
