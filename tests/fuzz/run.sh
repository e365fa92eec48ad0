#!/usr/bin/env bash
# Fuzzes rsd's parsers with libFuzzer, AddressSanitizer and UBSan (clang, libfuzzer-14-dev).
#   tests/fuzz/run.sh [MINUTES] [TARGET...]      (default: 10 minutes each, every target)
# The fuzz targets are built in an ASan+UBSan tree built by clang (the sanitizer tree's own
# configuration: its fuzz targets are libFuzzer binaries), build-fuzz/ unless RSD_FUZZ_BUILD names
# another (tests/sanitizers/run.sh passes its tree for the complete suite's 6 s per target); each
# runs for MINUTES, two at a time (RSD_FUZZ_JOBS), starting from its corpus in tests/fuzz/corpus/TARGET.
# A crash, leak, sanitizer report, timeout (10 s) or excess memory (2 GB) is written into that
# corpus as crash-*, timeout-*, leak-* or oom-*: the normal test run replays it (ctest -R
# fuzz_corpus), and fails, until the defect is fixed. New inputs that reach new code go to
# BUILD/fuzz-work/TARGET (--merge: also added to the corpus). A summary line per target
# (runs, seconds, corpus size, result) goes to stdout and BUILD/fuzz-summary.txt.
set -euo pipefail
src=$(cd "$(dirname "$0")/../.." && pwd)
build=${RSD_FUZZ_BUILD:-$src/build-fuzz}
jobs=${RSD_FUZZ_JOBS:-2}
merge=0
if [ "${1:-}" = "--merge" ]; then merge=1; shift; fi
minutes=${1:-10}
[ $# -gt 0 ] && shift
all="config calibration intrinsics scenario recording images_recording lcm_log lcm_message lcm_transport image gpmf sensor_csv gcsv replay"
targets=${*:-$all}
case $minutes in ''|*[!0-9.]*) echo "run.sh: MINUTES must be a number, not '$minutes'" >&2; exit 2 ;; esac
for t in $targets; do
  case " $all " in *" $t "*) ;; *) echo "run.sh: no fuzz target '$t' (targets: $all)" >&2; exit 2 ;; esac
done

if [ ! -f "$build/CMakeCache.txt" ]; then
  generator=()
  command -v ninja >/dev/null && generator=(-G Ninja)
  cmake -S "$src" -B "$build" "${generator[@]}" -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
        -DRSD_SANITIZE=address,undefined -DCMAKE_BUILD_TYPE=None >/dev/null
fi
# A tree configured otherwise (a normal tree, or the fuzz tree of earlier versions) holds no
# libFuzzer binaries: said, not run.
grep -qx 'RSD_SANITIZE:STRING=address,undefined' "$build/CMakeCache.txt" &&
  grep -q '^CMAKE_CXX_COMPILER:[A-Z]*=.*clang' "$build/CMakeCache.txt" ||
  { echo "run.sh: $build is not an ASan+UBSan tree built by clang: remove it, or name one with RSD_FUZZ_BUILD" >&2; exit 2; }
start=$(date +%s)
cmake --build "$build" -j"$(nproc)" --target $(for t in $targets; do printf 'fuzz_%s ' "$t"; done) >"$build/build.log" 2>&1 ||
  { tail -n 60 "$build/build.log" >&2; exit 1; }
echo "run.sh: fuzz targets built in $(( $(date +%s) - start )) s"

seconds=$(awk "BEGIN { print int($minutes * 60) }")
summary=$build/fuzz-summary.txt
this_run=$build/fuzz-this-run.txt
: >"$this_run"
fuzz_one() {
  t=$1
  corpus=$src/tests/fuzz/corpus/$t
  work=$build/fuzz-work/$t
  mkdir -p "$work"
  log=$build/fuzz-work/$t.log
  status=0
  # Leak checks on: a parser that leaks on bad input is a defect too.
  "$build/tests/fuzz/fuzz_$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
      -artifact_prefix="$corpus/" "$work" "$corpus" >"$log" 2>&1 || status=$?
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  size=$(find "$work" "$corpus" -type f | wc -l)
  result=clean; [ "$status" -eq 0 ] || result="DEFECT (status $status, see $log)"
  if [ "$merge" -eq 1 ] && [ "$status" -eq 0 ]; then
    "$build/tests/fuzz/fuzz_$t" -merge=1 "$corpus" "$work" >>"$log" 2>&1 || true
  fi
  line="$(date -u +%Y-%m-%dT%H:%MZ) fuzz_$t: ${runs:-0} runs in ${seconds} s, corpus $size inputs: $result"
  echo "$line"
  echo "$line" >>"$this_run"
  echo "$line" >>"$summary"
}
failed=0
running=0
for t in $targets; do
  fuzz_one "$t" &
  running=$((running + 1))
  if [ "$running" -ge "$jobs" ]; then wait -n; running=$((running - 1)); fi
done
wait
grep -q "DEFECT" "$this_run" && failed=1
exit $failed
