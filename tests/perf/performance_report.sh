#!/bin/sh
# Regenerates the measured part of docs/performance.md: runs the rectifier benchmark (5
# repetitions) and the end-to-end latency benchmark (mono8, nv12, then mono8 with the online
# calibration's estimator on at 120 fps and at 30 fps: docs/online-calibration.md) from a built tree and
# replaces the text between the two "generated" markers with their summaries, the machine and
# the load. Run on a quiet machine; the build should be Release.
#
#   tests/perf/performance_report.sh SOURCE_DIR BUILD_DIR
#   cmake --build build-perf --target performance_doc      # the same, from CMake
set -eu
src=$1
build=$2
doc="$src/docs/performance.md"
rect="$build/tests/dsp/rectify/bench_rs_rectifier"
e2e="$build/tests/daemon/bench_pipeline_latency"
for exe in "$rect" "$e2e"; do
  [ -x "$exe" ] || { echo "performance_report: $exe is missing: build it first (cmake --build $build --target benchmarks)" >&2; exit 2; }
done
grep -q '^<!-- generated: begin' "$doc" && grep -q '^<!-- generated: end' "$doc" ||
  { echo "performance_report: $doc lacks the generated markers" >&2; exit 2; }

out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "performance_report: load before: $(cut -d' ' -f1-3 /proc/loadavg)" >&2
echo "performance_report: bench_rs_rectifier (a few minutes) ..." >&2
"$rect" --benchmark_repetitions=5 --benchmark_min_time=0.2 --benchmark_enable_random_interleaving=true --benchmark_format=json \
  >"$out/rectifier.json" 2>"$out/rectifier.txt"
# Each end-to-end run: a name and its arguments.
runs="mono8 nv12 online online30"
args_of() {
  case $1 in
    online) echo "--online" ;;
    online30) echo "--online --fps 30" ;;
    *) echo "--format $1" ;;
  esac
}
for r in $runs; do
  echo "performance_report: bench_pipeline_latency $(args_of "$r") ..." >&2
  # shellcheck disable=SC2046  # the arguments are words on purpose
  "$e2e" $(args_of "$r") >"$out/e2e-$r.txt" 2>&1
done

cpu=$(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -n 1)
{
  echo '<!-- generated: begin (tests/perf/performance_report.sh; do not edit by hand) -->'
  echo
  echo "Measured $(date -u '+%Y-%m-%d %H:%M UTC') on $(nproc) cores, $cpu; load average before"
  echo "the run $(cut -d' ' -f1-3 /proc/loadavg | tr ' ' '/') (1/5/15 min); commit $(git -C "$src" rev-parse --short HEAD 2>/dev/null || echo unknown)."
  echo
  echo '### Rectifier (bench_rs_rectifier summary; ns per output pixel)'
  echo
  echo '```'
  sed -n '/^Summary/,$p' "$out/rectifier.txt"
  echo '```'
  for r in $runs; do
    echo
    echo "### End to end, $r (bench_pipeline_latency $(args_of "$r"))"
    echo
    echo '```'
    sed -n '/^End to end/,$p' "$out/e2e-$r.txt"
    echo '```'
  done
  echo
  echo '<!-- generated: end -->'
} >"$out/section.md"

awk -v section="$out/section.md" '
  /^<!-- generated: begin/ { while ((getline line < section) > 0) print line; skip = 1; next }
  /^<!-- generated: end/ { skip = 0; next }
  !skip { print }' "$doc" >"$out/doc.md"
cp "$out/doc.md" "$doc"
cp "$out/rectifier.json" "$build/bench_rs_rectifier.json"
echo "performance_report: $doc updated; Google Benchmark JSON in $build/bench_rs_rectifier.json" >&2
