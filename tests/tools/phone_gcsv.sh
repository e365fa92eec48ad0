#!/bin/sh
# Writes the phone recording's gyro (tests/data/real/phone-cc9/gyro.txt: wx wy wz t, rad/s and s on
# the phone's clock) as gyroflow's .gcsv would hold it: times in microseconds from the video's first
# frame (FIRST_FRAME_T, s), rates in units of 1e-4 rad/s, the source's readout (33.312 ms, top to
# bottom). Usage: phone_gcsv.sh GYRO_TXT FIRST_FRAME_T OUT_GCSV
set -e
awk -F '[ ,\t]+' -v t0="$2" '
  function round(x) { return x >= 0 ? int(x + 0.5) : -int(-x + 0.5) }
  BEGIN { print "GYROFLOW IMU LOG\nversion,1.3\nid,phone-cc9\norientation,XYZ\nframe_readout_time,33.312"
          print "frame_readout_direction,0\ntscale,0.000001\ngscale,0.0001\nt,gx,gy,gz" }
  NF >= 4 { printf "%d,%d,%d,%d\n", round(($4 - t0) * 1e6), round($1 * 1e4), round($2 * 1e4), round($3 * 1e4) }
' "$1" > "$3"
