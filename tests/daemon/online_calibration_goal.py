#!/usr/bin/env python3
"""The online calibration's goal through the daemon's own command line (issue 18).

The simulated camera hides rig physics from the daemon: its IMU clock runs 15 ms ahead of the
camera's, its rows are read with a line delay 20% longer than the nominal one the daemon is given
(a calibration file: the simulator's intrinsics, line delay 50 us against the true 60 us) and its
gyro reads 0.01 rad/s too much on every axis; the camera is shaken by hand (a wobble about
changing axes, no translation). `rsd -c CONFIG --duration 30` with calibration.online: apply
must converge within 10 s of the first frame (its log says when) and leave a state file
(rsd-calibration/1) holding the offset within 0.5 ms, the line delay within 3% and the bias
within 0.002 rad/s on each axis; run again, the daemon starts from that file.

Usage: online_calibration_goal.py RSD WORKDIR
"""
import math
import os
import re
import subprocess
import sys
from datetime import datetime

TRUE_OFFSET, TRUE_LINE_DELAY, TRUE_BIAS = 0.015, 60e-6, 0.01
NOMINAL_LINE_DELAY = 50e-6
FX = 320 / math.tan(math.radians(30))  # the simulator's 640x480 camera, 60 degrees across

CALIBRATION = f"""cam0:
  camera_model: pinhole
  intrinsics: [{FX!r}, {FX!r}, 319.5, 239.5]
  distortion_model: radtan
  distortion_coeffs: [0, 0, 0, 0]
  resolution: [640, 480]
  timeshift_cam_imu: 0
  rsd:
    format: rsd-calibration/1
    line_delay_s: {NOMINAL_LINE_DELAY!r}
    readout: top_to_bottom
"""

CONFIG = f"""source:
  driver: sim
  calibration_file: nominal.yaml
  sim:
    line_delay_s: {TRUE_LINE_DELAY!r}
    imu_time_offset_s: {TRUE_OFFSET!r}
    gyro_bias_rad_s: [{TRUE_BIAS}, {TRUE_BIAS}, {TRUE_BIAS}]
    angular_rate_rad_s: [0, 0, 0]
    velocity_m_s: [0, 0, 0]
    wobble_rad_s: 0.8
    wobble_hz: 0.9
    wobble_axes: [1, 0.8, 0.5]
    wobble_axes_hz: [1, 1.37, 0.71]
calibration:
  online: apply
  state_file: state.yaml
"""


def fail(why, log=""):
    sys.stdout.write(log)
    sys.exit(f"FAIL: {why}")


def number(text, key):
    m = re.search(rf"^\s*{key}:\s*(\S+)\s*$", text, re.M)
    if not m:
        fail(f"the state file has no {key}", text)
    return float(m.group(1))


def clock(line):
    m = re.match(r"\[(\d\d:\d\d:\d\d\.\d+)\]", line)
    return datetime.strptime(m.group(1), "%H:%M:%S.%f") if m else None


def main():
    rsd, work = sys.argv[1:3]
    os.makedirs(work, exist_ok=True)
    for name, text in (("nominal.yaml", CALIBRATION), ("online.yaml", CONFIG)):
        with open(os.path.join(work, name), "w") as f:
            f.write(text)
    state = os.path.join(work, "state.yaml")
    if os.path.exists(state):
        os.remove(state)
    run = subprocess.run([rsd, "-c", os.path.join(work, "online.yaml"), "--duration", "30", "--quiet"],
                         capture_output=True, text=True, timeout=120)
    log = run.stdout + run.stderr
    if run.returncode != 0:
        fail(f"rsd exited {run.returncode}", log)
    if os.environ.get("RSD_TEST_SANITIZER"):
        # Several times slower under a sanitizer: the run itself is the check (no report, exit
        # 0); the goal's timing and values are the normal tree's.
        if "online calibration" not in log:
            fail("the estimator said nothing", log)
        print(f"OK: ran clean under {os.environ['RSD_TEST_SANITIZER']} (the goal is checked in the normal tree)")
        return
    lines = log.splitlines()
    start = next((clock(l) for l in lines if "rsd: info: sim 640x480" in l), None)
    converged = next((clock(l) for l in lines if "online calibration converged" in l), None)
    if start is None or converged is None:
        fail("the log says neither the start nor a convergence", log)
    took = (converged - start).total_seconds()
    if not os.path.exists(state):
        fail("no state file written", log)
    text = open(state).read()
    offset = number(text, "timeshift_cam_imu")
    line_delay = number(text, "line_delay_s")
    bias = [float(v) for v in re.search(r"^\s*gyro_bias_rad_s:\s*\[([^\]]*)\]", text, re.M).group(1).split(",")]
    print(f"converged {took:.1f} s after the first frame; time offset {offset * 1e3:.3f} ms (true 15), line delay "
          f"{line_delay * 1e6:.3f} us (true 60, nominal 50), gyro bias {bias} (true 0.01)")
    errors = []
    if took > 10:
        errors.append(f"converged after {took:.1f} s (goal: 10)")
    if abs(offset - TRUE_OFFSET) > 0.5e-3:
        errors.append("time offset beyond 0.5 ms")
    if abs(line_delay / TRUE_LINE_DELAY - 1) > 0.03:
        errors.append("line delay beyond 3%")
    if len(bias) != 3 or any(abs(b - TRUE_BIAS) > 0.002 for b in bias):
        errors.append("gyro bias beyond 0.002 rad/s")
    if errors:
        fail("; ".join(errors), log + text)
    # A restart begins from what was learned.
    again = subprocess.run([rsd, "-c", os.path.join(work, "online.yaml"), "--duration", "2", "--quiet"],
                           capture_output=True, text=True, timeout=60)
    if again.returncode != 0 or f"online calibration: starting from {state}" not in again.stdout + again.stderr:
        fail("a restart did not start from the state file", again.stdout + again.stderr)
    print("OK: the state file holds the hidden offset, line delay and bias, and a restart starts from it")


if __name__ == "__main__":
    main()
