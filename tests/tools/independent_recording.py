#!/usr/bin/env python3
"""An independent check of rsd-diagnose: a gyro and matches recording written from the
recording format's text alone (docs/formats/recording-v1.md), with none of rsd's code (its
simulator agrees with its model by construction), diagnosed by the tool, its named effects
compared with the truth.

The camera turns under a random sum of sines in the IMU's axes, integrated as dR/dt = R [w]x
(a pan added, or the pictures following the rates low-passed: a stabiliser); it may translate
(a hand's shake, a forward flight). Each match is a ray at a random pixel of frame_a, to a point
at infinity or at a random distance, found in frame_b at the fixed point of the rows' read
times (the rolling-shutter constraint). Plain Python: no third-party module. The cases (CASES)
are a pinhole phone and a fisheye action camera (rotation only; CTests, label e2e), a hand-held
phone under parallax, a stabilised video and a drone's forward flight with a pan past points at
many depths (CTests, label slow).

  independent_recording.py --case NAME --rsd-diagnose PATH --work DIR [--set KEY=JSON ...]
  independent_recording.py --case NAME --work DIR --write-only
  independent_recording.py --case pinhole --pictures --set width=640 --set height=360 --set f=500 ...

--pictures writes the rig's frames rendered instead of matches (independent_pictures.py: an
images recording, which rsd-diagnose tracks itself); rotation-only cases.

--set writes a variant of the case (a user's rig the CTests do not hold), e.g. the drone's
gimbal steadier: --case drone --set rate=0.01; or at 60 fps: --set fps=60.

Exit status 0 when every goal holds, 1 when one does not (each says why), 2 on bad use.
"""
import argparse
import json
import math
import os
import random
import subprocess
import sys


# --- 3-vectors and 3x3 matrices as lists -------------------------------------------------

def mat_mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def mat_vec(a, v):
    return [sum(a[i][k] * v[k] for k in range(3)) for i in range(3)]


def transpose(a):
    return [[a[j][i] for j in range(3)] for i in range(3)]


def exp_so3(r):
    """Rodrigues: the rotation by |r| about r / |r|."""
    th = math.sqrt(sum(x * x for x in r))
    if th < 1e-12:
        return [[1, -r[2], r[1]], [r[2], 1, -r[0]], [-r[1], r[0], 1]]
    k = [x / th for x in r]
    c, s, v = math.cos(th), math.sin(th), 1 - math.cos(th)
    return [[c + k[0] * k[0] * v, k[0] * k[1] * v - k[2] * s, k[0] * k[2] * v + k[1] * s],
            [k[1] * k[0] * v + k[2] * s, c + k[1] * k[1] * v, k[1] * k[2] * v - k[0] * s],
            [k[2] * k[0] * v - k[1] * s, k[2] * k[1] * v + k[0] * s, c + k[2] * k[2] * v]]


def log_so3(m):
    c = max(-1.0, min(1.0, (m[0][0] + m[1][1] + m[2][2] - 1) / 2))
    th = math.acos(c)
    v = [(m[2][1] - m[1][2]) / 2, (m[0][2] - m[2][0]) / 2, (m[1][0] - m[0][1]) / 2]
    return v if th < 1e-9 else [x * th / math.sin(th) for x in v]


# --- the rig --------------------------------------------------------------------------------

# Each case: the camera and its truth; `expect` the effects a diagnosis must name; `remainder`
# None where it must be noise, else the signal it must be significant in; `may_miss` effects of
# the truth the data hardly hold, which may go unnamed (named, they meet the goals, but for a
# component whose stated sigma says the data cannot hold it to its goal, over a third of it: that
# one must lie within three of its sigma); `goals` whether the
# named values must meet the benchmark's goals (line delay 3%, offset 0.5 ms, bias 1 mrad/s).
# `honest`: parameters (time_offset_s, line_delay_s) whose named values must lie within three of the
# sigmas the report states of the truth, whether or not they meet the goals (one named without a
# stated sigma fails: the report's table must be read); `honest_within` that many sigmas instead of
# three (a recording whose value lay between two and three of a sigma too narrow).
# Optional: f_nominal, k_nominal (the nominal model's, where the truth differs), mount (the
# camera turned on its mount by this rotation vector), trans (a hand's translation, m), depth
# (points at log-uniform distances in this range, m; without it every point is at infinity),
# fwd (a forward flight, m/s), pan (rad, starting s: a raised-cosine pan over 2 s about the
# camera's y axis), stabilise_hz (the pictures follow the gyro's rates low-passed, zero phase,
# |G| = 1 / sqrt(1 + (f / stabilise_hz)^4)), duration, fps, per_pair, noise, gyro_hz, exposure
# (--pictures: each row the mean of its views over this many seconds centred on its read time),
# wall (--pictures: a wall this many metres ahead, which the translation moves past).
CASES = {
    # A phone-like pinhole camera: a readout the nominal model lacks, the clocks 15 ms apart, a
    # gyro bias; the gyro's axes a permutation of the camera's, 2 degrees off it (a calibration).
    'pinhole': dict(width=1280, height=720, f=1000.0, model='pinhole-radtan', k=[-0.05, 0.01],
                    line_delay=2.5e-5, offset=0.015, bias=[0.004, -0.003, 0.005], rate=0.6,
                    expect=['rolling_shutter', 'time_offset', 'gyro_bias'], remainder=None, goals=True),
    # A fisheye (equidistant) action camera, corners 70 degrees off the axis, its nominal lens
    # right: the clocks 30 ms apart, a bias, the readout known.
    'fisheye': dict(width=1280, height=960, f=420.0, model='pinhole-equi', k=[0.02, -0.01],
                    line_delay=2e-5, nominal_line_delay=2e-5, offset=-0.030, bias=[0.002, 0.004, -0.003],
                    rate=0.8, expect=['time_offset', 'gyro_bias'], remainder=None, goals=True),
    # A hand-held 1080p phone shaken by 5 cm past points 2-30 m away (no plane: the translation
    # nuisance's plane does not hold): the nominal focal length 12% short, barrel k1 -0.05 where
    # the nominal has none, a 16 ms readout, the clocks 50 ms apart, the camera turned 1.2 degrees.
    'phone-parallax': dict(width=1920, height=1080, f=1510.0, f_nominal=1330.0, model='pinhole-radtan',
                           k=[-0.05, 0.0], k_nominal=[0.0, 0.0], line_delay=1.5e-5, offset=0.05, bias=[0, 0, 0],
                           mount=[0.012, -0.015, 0.01], rate=0.5, trans=0.05, depth=[2.0, 30.0], duration=20.0,
                           per_pair=120, expect=['rolling_shutter', 'time_offset', 'focal_length',
                                                 'lens_distortion', 'mount_rotation'],
                           remainder='translation', goals=False),
    # A video stabilised in the camera by another smoothing than rsd's Gaussian: nothing to name.
    'stabilised': dict(width=1920, height=1080, f=1100.0, model='pinhole-radtan', k=[0.0, 0.0],
                       line_delay=1.5e-5, nominal_line_delay=1.5e-5, offset=0.0, bias=[0, 0, 0], rate=0.5,
                       stabilise_hz=1.5, duration=15.0, noise=0.4, expect=[], remainder='stabilisation',
                       goals=False),
    # A drone's gimbal camera flying forward at 8 m/s past points 20-200 m away, panning 0.8 rad at
    # 8 s: the clocks -58 ms apart, a bias of a few mrad/s, which a forward flight hardly shows
    # (a constant rate about the pan's axis moves the image as a sideways velocity does): it may
    # go unnamed, but named, it must be right (one plane's scene had it 29 mrad/s off).
    'drone': dict(width=854, height=480, f=540.0, model='pinhole-radtan', k=[0.0, 0.0], line_delay=3e-5,
                  nominal_line_delay=3e-5, offset=-0.058, bias=[0.003, -0.002, 0.004], rate=0.03, fwd=8.0,
                  pan=[0.8, 8.0], depth=[20.0, 200.0], duration=12.0, gyro_hz=400.0,
                  expect=['time_offset'], may_miss=['gyro_bias'], remainder='translation', goals=True),
}
DURATION_S, FPS, PER_PAIR, NOISE_PX, OUTLIERS, GYRO_HZ, GYRO_NOISE = 10.0, 30.0, 100, 0.5, 0.05, 200.0, 0.003
VARIANT_KEYS = {'fps', 'duration', 'per_pair', 'noise', 'gyro_hz', 'mount', 'trans', 'depth', 'fwd', 'pan',
                'stabilise_hz', 'f_nominal', 'k_nominal', 'nominal_line_delay', 'may_miss', 'honest', 'honest_within',
                'exposure', 'wall'}
INSTRUMENT_BIAS_PX = 0.03  # what a tracker's own bias reaches (docs/diagnosis.md)
PERMUTED = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]  # w_camera = R w_imu: the gyro's x is the camera's y


class Rig:
    def __init__(self, case, seed):
        self.c = case
        self.seed = seed
        self.rng = random.Random(seed)
        self.cx = (case['width'] - 1) / 2 + 3.0
        self.cy = (case['height'] - 1) / 2 - 2.0
        self.duration = case.get('duration', DURATION_S)
        self.fps = case.get('fps', FPS)
        self.imu_to_camera = mat_mul(exp_so3([0.02, -0.01, 0.03]), PERMUTED)  # what the yaml says
        self.true_imu_to_camera = mat_mul(exp_so3(case.get('mount', [0, 0, 0])), self.imu_to_camera)
        self.terms = [(ax, self.rng.uniform(0.3, 2.5), self.rng.uniform(0, 2 * math.pi), self.rng.gauss(0, 1))
                      for ax in range(3) for _ in range(4)]
        power = [sum(am * am / 2 for a, _, _, am in self.terms if a == ax) for ax in range(3)]
        self.gain = [case['rate'] / math.sqrt(p) for p in power]
        self.shake = [(ax, self.rng.uniform(0.3, 1.5), self.rng.uniform(0, 2 * math.pi))
                      for ax in range(3) for _ in range(2)] if 'trans' in case else []
        self.t0 = 0.2
        self.dt = 1 / 2000.0
        self._integrate(self.t0 - 0.5, self.t0 + self.duration + 1.0)
        self.forward = mat_vec(self.r_camera(0.0), [0.0, 0.0, case.get('fwd', 0.0)])  # world axes

    def pan(self, t):
        """The pan's rate in the IMU's axes (zero without one)."""
        if 'pan' not in self.c or not (self.c['pan'][1] <= t <= self.c['pan'][1] + 2):
            return [0.0, 0.0, 0.0]
        wy = self.c['pan'][0] / 2 * (1 - math.cos(math.pi * (t - self.c['pan'][1])))
        return mat_vec(transpose(self.true_imu_to_camera), [0.0, wy, 0.0])

    def w_imu(self, t, stabiliser=False):
        """The IMU's rate; with `stabiliser`, the rate the pictures follow."""
        fc = self.c.get('stabilise_hz', 0.0) if stabiliser else 0.0
        w = self.pan(t)
        for ax, fr, ph, am in self.terms:
            g = 1.0 if fc <= 0 else 1 / math.sqrt(1 + (fr / fc) ** 4)
            w[ax] += g * self.gain[ax] * am * math.sin(2 * math.pi * fr * t + ph)
        return w

    def position(self, t):
        """The camera's position in the world (m)."""
        p = [x * t for x in self.forward]
        for ax, fr, ph in self.shake:
            p[ax] += self.c['trans'] * math.sin(2 * math.pi * fr * t + ph) / math.sqrt(2)
        return p

    def _integrate(self, t_lo, t_hi):
        self.t_lo = t_lo
        r = [[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]]
        self.orient = []
        t = t_lo
        while t <= t_hi + self.dt:
            self.orient.append(r)
            w = self.w_imu(t + self.dt / 2, stabiliser=True)  # the orientation the pictures follow
            r = mat_mul(r, exp_so3([x * self.dt for x in w]))
            t += self.dt

    def r_imu(self, t):
        """The IMU's orientation as the pictures follow it (smoothed under a stabiliser)."""
        x = (t - self.t_lo) / self.dt
        i = int(math.floor(x))
        a, b = self.orient[i], self.orient[i + 1]
        step = log_so3(mat_mul(transpose(a), b))
        return mat_mul(a, exp_so3([(x - i) * s for s in step]))

    def r_camera(self, t_motion):
        return mat_mul(self.r_imu(t_motion), transpose(self.true_imu_to_camera))

    def project(self, p):
        k, f = self.c['k'], self.c['f']
        if self.c['model'] == 'pinhole-equi':
            r = math.hypot(p[0], p[1])
            th = math.atan2(r, p[2])
            thd = th * (1 + k[0] * th ** 2 + k[1] * th ** 4)
            s = thd / r if r > 1e-12 else 1 / p[2]
            return f * p[0] * s + self.cx, f * p[1] * s + self.cy
        x, y = p[0] / p[2], p[1] / p[2]
        r2 = x * x + y * y
        s = 1 + k[0] * r2 + k[1] * r2 * r2
        return f * x * s + self.cx, f * y * s + self.cy

    def ray(self, u, v):
        """The unit direction seen at pixel (u, v)."""
        k, f = self.c['k'], self.c['f']
        xd, yd = (u - self.cx) / f, (v - self.cy) / f
        if self.c['model'] == 'pinhole-equi':
            thd = math.hypot(xd, yd)
            th = thd
            for _ in range(30):
                th -= (th * (1 + k[0] * th ** 2 + k[1] * th ** 4) - thd) / (1 + 3 * k[0] * th ** 2 + 5 * k[1] * th ** 4)
            if thd < 1e-12:
                return [0.0, 0.0, 1.0]
            return [math.sin(th) * xd / thd, math.sin(th) * yd / thd, math.cos(th)]
        x, y = xd, yd
        for _ in range(40):
            r2 = x * x + y * y
            s = 1 + k[0] * r2 + k[1] * r2 * r2
            x, y = xd / s, yd / s
        n = math.sqrt(x * x + y * y + 1)
        return [x / n, y / n, 1 / n]

    def motion_time(self, frame, v):
        return self.t0 + frame / self.fps + self.c['line_delay'] * v + self.c['offset']

    def match(self, frame):
        """One match of frame and frame + 1, or None when the point leaves the picture."""
        w, h = self.c['width'], self.c['height']
        ua, va = self.rng.uniform(0, w - 1), self.rng.uniform(0, h - 1)
        d = self.ray(ua, va)
        if math.atan2(math.hypot(d[0], d[1]), d[2]) > 1.4:
            return None
        ta = self.motion_time(frame, va)
        if 'depth' in self.c:  # a point at a distance along the ray
            lo, hi = self.c['depth']
            dist = math.exp(self.rng.uniform(math.log(lo), math.log(hi)))
            world = [x + dist * y for x, y in zip(self.position(ta), mat_vec(self.r_camera(ta), d))]
        else:  # a point at infinity: rotation only
            world = mat_vec(self.r_camera(ta), d)
        seen = self.seen_in(frame + 1, world, va, 'depth' in self.c)
        if seen is None:
            return None
        ub, vb = seen
        if not (0 <= ub <= w - 1 and 0 <= vb <= h - 1):
            return None
        g, noise = self.rng.gauss, self.c.get('noise', NOISE_PX)
        if self.rng.random() < OUTLIERS:
            ub, vb = self.rng.uniform(0, w - 1), self.rng.uniform(0, h - 1)
        return ua + g(0, noise), va + g(0, noise), ub + g(0, noise), vb + g(0, noise)

    def seen_in(self, frame, world, v_start, at_distance):
        """The pixel at which `frame` sees the point `world` (a direction for a point at infinity,
        else a place, m): the fixed point of the rows' read times (the rolling-shutter constraint)
        from row v_start; None when the point is behind a pinhole camera."""
        v = v_start
        for _ in range(20):
            t = self.motion_time(frame, v)
            seen = [x - y for x, y in zip(world, self.position(t))] if at_distance else world
            p = mat_vec(transpose(self.r_camera(t)), seen)
            if p[2] <= 0.05 and self.c['model'] != 'pinhole-equi':
                return None
            u, v_new = self.project(p)
            done = abs(v_new - v) < 1e-7
            v = v_new
            if done:
                break
        return u, v

    def frames(self):
        return int(self.duration * self.fps)

    def write(self, out, pictures=False):
        """The recording: matches, or with `pictures` the frames rendered (independent_pictures.py)."""
        os.makedirs(out, exist_ok=True)
        frames = self.frames()
        with open(os.path.join(out, 'frames.csv'), 'w') as f:
            f.write('frame,t\n')
            for k in range(frames):
                f.write(f'{k},{self.t0 + k / self.fps:.9f}\n')
        if pictures:
            from independent_pictures import write_pictures
            write_pictures(self, out)
        else:
            self.write_matches(out)
        self.write_gyro(out)
        self.write_yaml(out, 'images' if pictures else 'matches', 'images.csv' if pictures else 'matches.csv')

    def write_matches(self, out):
        frames = self.frames()
        with open(os.path.join(out, 'matches.csv'), 'w') as f:
            f.write('frame_a,ua,va,frame_b,ub,vb\n')
            for k in range(frames - 1):
                n = 0
                while n < self.c.get('per_pair', PER_PAIR):
                    m = self.match(k)
                    if m:
                        f.write(f'{k},{m[0]:.4f},{m[1]:.4f},{k + 1},{m[2]:.4f},{m[3]:.4f}\n')
                        n += 1

    def write_gyro(self, out):
        with open(os.path.join(out, 'gyro.csv'), 'w') as f:
            f.write('t,wx,wy,wz\n')
            t = 0.0
            while t < self.t0 + self.duration + 0.5:
                w = self.w_imu(t)  # w_true = w_measured - b
                f.write('{:.9f},{:.9f},{:.9f},{:.9f}\n'.format(
                    t, *[w[i] + self.c['bias'][i] + self.rng.gauss(0, GYRO_NOISE) for i in range(3)]))
                t += 1 / self.c.get('gyro_hz', GYRO_HZ)

    def write_yaml(self, out, kind, file):
        c = self.c
        f_nominal, k_nominal = c.get('f_nominal', c['f']), c.get('k_nominal', c['k'])
        rows = ', '.join(f'{x:.12f}' for row in self.imu_to_camera for x in row)
        with open(os.path.join(out, 'recording.yaml'), 'w') as f:
            f.write(f"""format: rsd-recording/1
camera:
  width: {c['width']}
  height: {c['height']}
  fx: {f_nominal}
  fy: {f_nominal}
  cx: {self.cx}
  cy: {self.cy}
  distortion: [{k_nominal[0]}, {k_nominal[1]}, 0, 0]
  model: {c['model']}
timing:
  frame_rate_hz: {self.fps}
  line_delay_s: {c.get('nominal_line_delay', 0.0)}
  readout: top_to_bottom
  time_offset_s: 0.0
  drift_ppm: 0.0
motion:
  kind: gyro
  file: gyro.csv
  imu_to_camera: [{rows}]
observations:
  kind: {kind}
  file: {file}
frames: frames.csv
""")


# --- the goals ------------------------------------------------------------------------------

def stated_sigmas(report_dir):
    """(parameter -> (value, sigma)) from the report's table of named effects."""
    out = {}
    with open(os.path.join(report_dir, 'index.md')) as f:
        for line in f:
            cells = [c.strip() for c in line.strip().strip('|').split('|')]
            if len(cells) == 5 and cells[1].startswith('`') and cells[1].endswith('`'):
                try:
                    out[cells[1].strip('`')] = (float(cells[2]), float(cells[3]))
                except ValueError:
                    pass
    return out


HONEST_PARAMS = ('time_offset_s', 'line_delay_s')


def outside_sigmas(case, named, sigmas):
    """The `honest` parameters named further from the truth than `honest_within` (three) of their
    stated sigmas, or named without a sigma in the report (a check that found nothing to check
    must not pass)."""
    truth = {'time_offset_s': case['offset'], 'line_delay_s': case['line_delay']}
    within = float(case.get('honest_within', 3))
    named_params = {k for params in named.values() for k in params}
    bad = []
    for name in case.get('honest', []):
        if name in named_params and name not in sigmas:
            bad.append(f"{name} is named but the report states no sigma for it")
        if name in sigmas:
            value, sigma = sigmas[name]
            if abs(value - truth[name]) > within * sigma:
                bad.append(f"{name} {value} +- {sigma}: {abs(value - truth[name]) / sigma:.1f} of its sigmas from the truth {truth[name]} (at most {within:g})")
    return bad


def check(case, d, sigmas=None):
    """What does not hold, one line each."""
    bad = []
    named = {e['name']: e['params'] for e in d['effects']}
    if sigmas is not None:
        bad += outside_sigmas(case, named, sigmas)
    truth = set(case['expect']) | set(case.get('may_miss', []))
    if not set(case['expect']) <= set(named) <= truth:
        bad.append(f"named {sorted(named)}, the truth is {sorted(truth)}" +
                   (f" ({sorted(case['may_miss'])} may go unnamed)" if case.get('may_miss') else ''))
    if case['goals']:
        bad += missed_goals(case, named, sigmas)
    significant, signals = d['remainder']['significant'], [l['signal'] for l in d['remainder']['located']]
    if case['remainder'] is None and significant:
        bad.append('the remainder is called significant: ' + json.dumps(d['remainder']))
    if case['remainder'] is not None and not (significant and case['remainder'] in signals):
        bad.append(f"the remainder must be significant in {case['remainder']}: " + json.dumps(d['remainder']))
    floor = d['remainder']['expected_rms_px']
    if case.get('pictures'):  # the tracker's own field, up to the instrument's bias, is not the model's
        floor = math.hypot(floor, INSTRUMENT_BIAS_PX)
    if case['remainder'] is None and d['heldout']['final_rms_px'] > 1.1 * floor:
        bad.append(f"held out {d['heldout']['final_rms_px']} px, noise alone {d['remainder']['expected_rms_px']} px" +
                   (f" ({floor:.4f} with the tracker's own bias)" if case.get('pictures') else ''))
    # Never told its axes are wrong; where nothing else is left, clearly told they are right.
    axes = d.get('imu_axes', '')
    confirmed = axes.endswith(': motion.imu_to_camera')
    if 'NOT motion.imu_to_camera' in axes or (case['remainder'] is None and not confirmed):
        bad.append('the gyro\'s axes: ' + axes)
    return bad


def within_goal(case, effect, param, error, goal, sigmas):
    """Whether a named value `error` from the truth meets its `goal`: within it, or, for an effect
    the case says the data hardly hold (may_miss), within three of its stated sigma where that
    sigma is over a third of the goal (the report says the data cannot hold it to the goal). A
    drone's bias about the pan's axis, which a sideways velocity can stand in for, came out 1.9
    mrad/s off at a stated sigma of 4.1 (seed 5), the roll's 0.23 at 0.54: the data hold the
    roll. One plane's stand-in, 29 mrad/s off at a sigma of 2.3, fails either way."""
    if abs(error) <= goal:
        return True
    if effect not in case.get('may_miss', []) or not sigmas or param not in sigmas:
        return False
    sigma = sigmas[param][1]
    return sigma > goal / 3 and abs(error) <= 3 * sigma


def missed_goals(case, named, sigmas=None):
    """The named values beyond the benchmark's goals."""
    bad = []
    if 'rolling_shutter' in named and abs(named['rolling_shutter']['line_delay_s'] / case['line_delay'] - 1) > 0.03:
        bad.append(f"line delay {named['rolling_shutter']['line_delay_s']}, the truth {case['line_delay']} (goal 3%)")
    if 'time_offset' in named and abs(named['time_offset']['time_offset_s'] - case['offset']) > 5e-4:
        bad.append(f"time offset {named['time_offset']['time_offset_s']}, the truth {case['offset']} (goal 0.5 ms)")
    if 'gyro_bias' in named:
        got = [named['gyro_bias'][k] for k in ('bx', 'by', 'bz')]
        if not all(within_goal(case, 'gyro_bias', k, g - t, 1e-3, sigmas)
                   for k, g, t in zip(('bx', 'by', 'bz'), got, case['bias'])):
            bad.append(f"gyro bias {got}, the truth {case['bias']} (goal 1 mrad/s a component" +
                       (", or within three of its stated sigma where that is over a third of the goal)"
                        if 'gyro_bias' in case.get('may_miss', []) else ")"))
    return bad


# The tracker's matches on the rendered pictures against the rig's truth, px a coordinate: the
# median error, the robust spread (1.4826 x MAD) and the error's share of the flow. Measured on
# the pinhole case at 640 x 360 (seed 1): 0.001, 0.027 and 0.00016.
TRACKER_GOALS = {'median': 0.005, 'spread': 0.05, 'scale': 0.001}


def check_tracker(rig, rec, rsd_extract, work):
    """rsd-extract's matches of the pictures against the truth: what does not hold, one line each."""
    from independent_pictures import tracker_errors
    out = os.path.join(work, 'tracked-' + os.path.basename(rec))
    run = subprocess.run([rsd_extract, rec, out], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if run.returncode != 0:
        return [f'rsd-extract exited {run.returncode}: ' + run.stdout[-2000:]]
    n, median, spread, scale = tracker_errors(rig, os.path.join(out, 'matches.csv'))
    print(f'tracker against the truth ({n} matches): median error ({median[0]:.4f}, {median[1]:.4f}) px, '
          f'spread ({spread[0]:.4f}, {spread[1]:.4f}) px, share of the flow ({scale[0]:.5f}, {scale[1]:.5f})')
    bad = []
    for name, values in (('median', median), ('spread', spread), ('scale', scale)):
        if max(abs(x) for x in values) > TRACKER_GOALS[name]:
            bad.append(f'tracker {name} {values}: over its goal {TRACKER_GOALS[name]}')
    return bad


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--case', choices=sorted(CASES), required=True)
    ap.add_argument('--rsd-diagnose', help='the rsd-diagnose binary')
    ap.add_argument('--write-only', action='store_true', help='write the recording (WORK/recording-CASE) and stop')
    ap.add_argument('--work', required=True, help='a directory for the recording and the diagnosis')
    ap.add_argument('--seed', type=int, default=1)
    ap.add_argument('--pictures', action='store_true',
                    help='write an images recording: the frames rendered (a texture at infinity, each row at its '
                         'own read time; independent_pictures.py) instead of matches; rotation-only cases')
    ap.add_argument('--rsd-extract', help='with --pictures: also track the pictures with this rsd-extract and '
                    'check its matches against the rig\'s truth (see TRACKER_GOALS)')
    ap.add_argument('--set', action='append', default=[], metavar='KEY=JSON',
                    help='a variant of the case: one of its keys (or fps, duration, per_pair, noise, gyro_hz) '
                         'set to a JSON value, e.g. --set offset=0.03 --set fps=60 (repeatable)')
    a = ap.parse_args()
    case = dict(CASES[a.case])
    for kv in a.set:
        key, _, value = kv.partition('=')
        if key not in set(case) | VARIANT_KEYS:
            ap.error(f"--set {kv}: no key '{key}' in case {a.case} (its keys: {', '.join(sorted(set(case) | VARIANT_KEYS))})")
        try:
            case[key] = json.loads(value)
        except json.JSONDecodeError as e:
            ap.error(f'--set {kv}: the value is not JSON ({e})')
    if not set(case.get('honest', [])) <= set(HONEST_PARAMS):
        ap.error(f"honest: only {', '.join(HONEST_PARAMS)} can be checked against the truth, not {case['honest']}")
    case['pictures'] = a.pictures
    rec = os.path.join(a.work, 'recording-' + a.case)
    if a.rsd_extract and not a.pictures:
        ap.error('--rsd-extract tracks pictures: it needs --pictures')
    if a.rsd_extract and case.get('wall'):
        ap.error('--rsd-extract: the truth of a match is computed for a scene at infinity, not a wall')
    rig = Rig(case, a.seed)
    try:
        rig.write(rec, pictures=a.pictures)
    except ValueError as e:
        ap.error(f'--case {a.case}: {e}')
    tracker_bad = check_tracker(rig, rec, a.rsd_extract, a.work) if a.rsd_extract else []
    if a.write_only:
        print('wrote ' + rec)
        for b in tracker_bad:
            print('FAIL: ' + b)
        return 1 if tracker_bad else 0
    if not a.rsd_diagnose:
        ap.error('--rsd-diagnose is needed unless --write-only')
    out = os.path.join(a.work, 'diagnosis-' + a.case + '.json')
    report = os.path.join(a.work, 'report-' + a.case)
    reads_sigmas = bool(case.get('honest') or case.get('may_miss'))
    run = subprocess.run([a.rsd_diagnose, rec, '--json', out] + (['--report', report] if reads_sigmas else []),
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if run.returncode != 0:
        print(run.stdout[-4000:])
        print(f'rsd-diagnose exited {run.returncode}')
        return 1
    with open(out) as f:
        d = json.load(f)
    print(json.dumps({'effects': d['effects'], 'heldout': d['heldout'], 'remainder': d['remainder'],
                      'imu_axes': d.get('imu_axes')}, indent=1))
    bad = tracker_bad + check(case, d, stated_sigmas(report) if reads_sigmas else None)
    for b in bad:
        print('FAIL: ' + b)
    print('independent recording (' + a.case + '): ' + ('FAIL' if bad else 'all goals hold'))
    return 1 if bad else 0


if __name__ == '__main__':
    sys.exit(main())
