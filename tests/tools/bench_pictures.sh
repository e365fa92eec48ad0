#!/bin/bash
# Issue 34's speed goal from pictures (a benchmark, not a test; docs/diagnosis.md, "Speed"): a
# recording of 1920x1080 frames at 30 fps, rendered by rsd-sim from the matches-kind end-to-end
# scenario (config/scenarios/extract-matches-rolling-shutter.yaml at 1080p, a 2e-5 s line delay),
# extracted (features tracked on at most --track-pairs frame pairs) and diagnosed; prints the
# CPU time of each step. A minute's log is 3.7 GB and takes about 9 minutes to render.
# A frame size other than 1080p (SIZE, e.g. 1280x720) keeps the field of view and the readout time.
# SUPERSAMPLE 1 renders about twice as fast as rsd-sim's default 2 (0.17 s a 1080p frame of one
# core; ten minutes of 1080p are a 37 GB log), at the price of aliased texture, which the tracker
# sees as more noise (0.33 px against 0.10).
# Usage: tests/tools/bench_pictures.sh BUILD_DIR [SECONDS=60] [WORK_DIR=a new temporary directory] [SIZE=1920x1080]
#                                      [SUPERSAMPLE=2]
set -euo pipefail
build=${1:?usage: bench_pictures.sh BUILD_DIR [SECONDS] [WORK_DIR] [SIZE] [SUPERSAMPLE]}
seconds=${2:-60}
work=${3:-$(mktemp -d)}
size=${4:-1920x1080}
supersample=${5:-2}
width=${size%x*} height=${size#*x}
f=$(awk "BEGIN{print 1500 * $width / 1920}")
cx=$(awk "BEGIN{print ($width - 1) / 2}") cy=$(awk "BEGIN{print ($height - 1) / 2}")
line_delay=$(awk "BEGIN{print 2.0e-5 * 1080 / $height}")
here=$(cd "$(dirname "$0")/../.." && pwd)
mkdir -p "$work"
sed -e "s/^duration_s: .*/duration_s: $seconds/" \
    -e "s/^camera: .*/camera: {width: $width, height: $height, fx: $f, fy: $f, cx: $cx, cy: $cy, distortion: [0, 0, 0, 0]}/" \
    -e "s/line_delay_s: 5.0e-5/line_delay_s: $line_delay/" \
    "$here/config/scenarios/extract-matches-rolling-shutter.yaml" > "$work/scenario.yaml"
grep '^camera:' "$work/scenario.yaml" > "$work/nominal.yaml"
TIMEFORMAT="%U s user + %S s system (%R s wall)"
if [ ! -s "$work/run.lcmlog" ]; then
  echo "rendering ${seconds} s of ${size} (${supersample}x${supersample} samples a pixel) into $work/run.lcmlog ..."
  "$build/tools/rsd-sim" lcm "$work/scenario.yaml" "$work/run.lcmlog" --supersample "$supersample" > "$work/render.log" 2>&1
fi
rm -rf "$work/rec"
echo -n "rsd-extract: "
{ time "$build/tools/rsd-extract" "$work/run.lcmlog" "$work/rec" --nominal "$work/nominal.yaml" --kind matches \
    > "$work/extract.log" 2>&1; } 2>&1
grep -a "tracking\|matches over" "$work/extract.log" | tr '\r' '\n' | grep -v "\[#" || true
echo -n "rsd-diagnose: "
{ time "$build/tools/rsd-diagnose" "$work/rec" --json "$work/diagnosis.json" > "$work/diagnose.log" 2>&1; } 2>&1
grep -a "baseline RMS" "$work/diagnose.log" || tail -3 "$work/diagnose.log"
