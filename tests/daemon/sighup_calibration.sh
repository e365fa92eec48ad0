#!/bin/sh
# SIGHUP through rsd's command line: a new calibration file is applied between two frames, a bad
# one (another resolution) is refused naming why and the running one kept, and a changed
# configuration restarts the pipeline; the daemon runs to its frame limit and exits 0.
#   sighup_calibration.sh RSD WORKDIR
rsd=$1; dir=$2
rm -rf "$dir" && mkdir -p "$dir" && cd "$dir" || exit 1
printf 'source:\n  driver: sim\n  sim: {width: 160, height: 120, fps: 30}\n' > rsd.yaml
cal() {  # cal LINE_DELAY WIDTH HEIGHT
  printf 'cam0:\n  camera_model: pinhole\n  intrinsics: [140, 140, 79.5, 59.5]\n  distortion_model: radtan\n  distortion_coeffs: [0, 0, 0, 0]\n  resolution: [%s, %s]\n  timeshift_cam_imu: 0.004\n  rsd:\n    format: rsd-calibration/1\n    line_delay_s: %s\n' "$2" "$3" "$1" > cal.yaml
}
cal 1.0e-4 160 120
# Each step waits for the daemon's answer to the one before (not for a fixed time: a sanitizer
# build starts and answers several times slower), and signals again each second until the
# answer comes (a SIGHUP while the previous calibration is still being taken up is refused
# with "send SIGHUP again").
scale=${RSD_TEST_TIME_SCALE:-1}
said() {  # said TEXT: wait up to 10 s (times the scale) for TEXT in the daemon's output
  i=0
  while [ $i -lt $((100 * scale)) ]; do
    grep -q "$1" out.txt && return 0
    sleep 0.1; i=$((i + 1))
  done
  return 1
}
hup_until() {  # hup_until TEXT: SIGHUP, again each second, until TEXT is in the output
  i=0
  while [ $i -lt $((10 * scale)) ]; do
    kill -HUP $pid
    j=0
    while [ $j -lt 10 ]; do grep -q "$1" out.txt && return 0; sleep 0.1; j=$((j + 1)); done
    i=$((i + 1))
  done
  return 1
}
"$rsd" -c rsd.yaml --calibration cal.yaml --frames 150 --quiet > out.txt 2>&1 &
pid=$!
said 'rsd: info: sim 160x120'; sleep 0.5
cal 1.5e-4 160 120; hup_until 'calibration reloaded'
cal 1.5e-4 320 240; hup_until 'says 320x240'
printf 'source:\n  driver: sim\n  sim: {width: 160, height: 120, fps: 60}\n' > rsd.yaml; cal 1.5e-4 160 120
hup_until 'configuration reloaded: restarting the pipeline'
wait $pid; rc=$?
cat out.txt
[ $rc -eq 0 ] || { echo "sighup: rsd exited with $rc"; exit 1; }
grep -q 'calibration reloaded: applied from the next frame' out.txt || { echo "sighup: the new calibration was not applied"; exit 1; }
grep -q "reload refused, keeping the running calibration: cal.yaml (cam0) says 320x240, but the camera delivers 160x120" out.txt ||
  { echo "sighup: the bad calibration was not refused by name"; exit 1; }
grep -q 'configuration reloaded: restarting the pipeline' out.txt || { echo "sighup: the changed configuration did not restart"; exit 1; }
echo "sighup: ok"
