"""Pictures for independent_recording.py's rig: an images recording rendered from the recording
format's text alone, with none of rsd's code (its renderer, rsd-sim's, shares its model).

The scene is a texture at infinity: a cube of random multi-scale grey values about the camera
(a direction's value is on the face its largest component points to, in the axes of the camera's
mid-recording orientation), so only rotation moves it, and a fisheye's rays past 90 degrees see
it too. Row v of frame k is read at the rig's motion time of that row (the
frame's time + line delay x v + the clock offset), so the rolling shutter is in the pixels
themselves: each row's rays turned by the camera's orientation at its own time, through the
rig's lens (its inverse projection, radial-tangential). Point-sampled at pixel centres (the
recording format's (0, 0) is the top-left pixel's centre) from a bilinear texture whose finest
texel is 1.5 px at the picture's centre, with 2 grey levels of noise; written as 8-bit PNG
(zlib, no third-party module). A case's points at random depths are refused; with the case
key `wall` (m) the camera's translation (`trans`, `fwd`) moves past a wall that far ahead of
its mid-recording place (the front face's texture, a ray's point on it over its distance):
parallax of one plane, in the pixels.
"""
import csv
import os
import random
import statistics
import struct
import sys
import zlib
from array import array

from independent_recording import mat_mul, mat_vec, transpose

TEXEL_PX = 1.5  # the finest texel at the picture's centre
OCTAVES = ((1, 0.25), (4, 0.35), (16, 0.4))  # (cell in texels, weight)
NOISE_DN = 2.0


def png(path, w, h, grey):
    """An 8-bit grey PNG of w x h bytes."""
    raw = b''.join(b'\x00' + bytes(grey[v * w:(v + 1) * w]) for v in range(h))

    def chunk(tag, data):
        return struct.pack('>I', len(data)) + tag + data + struct.pack('>I', zlib.crc32(tag + data) & 0xffffffff)
    with open(path, 'wb') as f:
        f.write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 0, 0, 0, 0)) +
                chunk(b'IDAT', zlib.compress(raw, 1)) + chunk(b'IEND', b''))


class Scene:
    """The texture at infinity, seen through the rig."""

    def __init__(self, rig, seed):
        c = rig.c
        if 'depth' in c:
            raise ValueError(f"pictures render a scene at infinity: this case has points at depths {c['depth']}")
        self.rig, self.w, self.h = rig, c['width'], c['height']
        self.rays = [[rig.ray(u, v) for u in range(self.w)] for v in range(self.h)]
        t_ref = rig.t0 + rig.duration / 2
        self.r_ref_t = transpose(rig.r_camera(t_ref))
        self.p_ref = rig.position(t_ref)
        self.wall = c.get('wall', 0.0)  # m ahead of the camera's mid-recording place; 0: none
        self.texel = TEXEL_PX / c['f']
        self.n = int(2 / self.texel) + 2  # texels along a face's side
        rng = random.Random(seed * 7919 + 17)
        self.faces = [self._texture(self.n, rng) for _ in range(6)]
        self.noise = [rng.gauss(0, NOISE_DN) for _ in range(65536)]
        self.rng = rng

    def turn(self, frame, v, shift=0.0):
        """Row v of `frame` `shift` s after its read time, in the reference orientation's axes:
        R_ref^T R(t_row + shift)."""
        return mat_mul(self.r_ref_t, self.rig.r_camera(self.rig.motion_time(frame, v) + shift))

    @staticmethod
    def _texture(n, rng):
        """One face, n x n grey values 0-255: bilinear random grids at three scales, summed,
        contrast stretched."""
        tex = [[0.0] * n for _ in range(n)]
        for cell, weight in OCTAVES:
            g = [[rng.random() for _ in range(n // cell + 2)] for _ in range(n // cell + 2)]
            for j in range(n):
                y = j / cell
                jj = int(y)
                fy = y - jj
                a, b, row = g[jj], g[jj + 1], tex[j]
                for i in range(n):
                    x = i / cell
                    ii = int(x)
                    fx = x - ii
                    p = a[ii] + fx * (a[ii + 1] - a[ii])
                    q = b[ii] + fx * (b[ii + 1] - b[ii])
                    row[i] += weight * (p + fy * (q - p))
        return [array('f', [min(250.0, max(5.0, 128 + 2.5 * 255 * (x - 0.5))) for x in row]) for row in tex]

    def render(self, frame):
        """Frame `frame` as w x h grey bytes, each row at its own read time; with the case's
        `exposure` (s), each row the mean of its views over that time centred on it (one a ms)."""
        w, exposure = self.w, self.rig.c.get('exposure', 0.0)
        k = max(1, round(exposure / 1e-3))
        shifts = [exposure * ((i + 0.5) / k - 0.5) for i in range(k)]
        noise, n0 = self.noise, self.rng.randrange(65536)
        out = bytearray(w * self.h)
        for v in range(self.h):
            acc = [0.0] * w
            for shift in shifts:
                self._add_row(self.turn(frame, v, shift), self.place(frame, v, shift), self.rays[v], acc)
            base = v * w
            for u in range(w):
                g = acc[u] / k + noise[(n0 + base + u) & 65535]
                out[base + u] = 0 if g < 0 else 255 if g > 255 else int(g + 0.5)
        return out

    def place(self, frame, v, shift=0.0):
        """The camera's place at row v's read time + shift, in the reference axes (m)."""
        p = self.rig.position(self.rig.motion_time(frame, v) + shift)
        return mat_vec(self.r_ref_t, [a - b for a, b in zip(p, self.p_ref)])

    def _add_row(self, m, place, rays, acc):
        """Adds the grey values the rays see turned by m from `place` to acc. A ray that meets
        the wall (the plane z = wall in the reference axes, within the front face's square at
        its distance) sees the front face's texture at its point over the wall's distance;
        any other its direction's value, on the cube face its largest component points to, at
        the other two over it."""
        faces, scale, half, wall = self.faces, 1 / self.texel, (self.n - 2) / 2, self.wall
        (m00, m01, m02), (m10, m11, m12), (m20, m21, m22) = m
        px, py, pz = place
        for u in range(len(acc)):
            x, y, z = rays[u]
            dx = m00 * x + m01 * y + m02 * z
            dy = m10 * x + m11 * y + m12 * z
            dz = m20 * x + m21 * y + m22 * z
            ax, ay, az = abs(dx), abs(dy), abs(dz)
            hit = False
            if wall > 0 and dz > 0:
                k = (wall - pz) / dz
                sx, sy = (px + k * dx) / wall, (py + k * dy) / wall
                hit = -1 < sx < 1 and -1 < sy < 1
            if hit:
                tex = faces[1]
            elif az >= ax and az >= ay:
                tex, sx, sy = faces[dz > 0], dx / az, dy / az
            elif ax >= ay:
                tex, sx, sy = faces[2 + (dx > 0)], dz / ax, dy / ax
            else:
                tex, sx, sy = faces[4 + (dy > 0)], dx / ay, dz / ay
            sx = sx * scale + half
            sy = sy * scale + half
            i, j = int(sx), int(sy)
            fx, fy = sx - i, sy - j
            a, b = tex[j], tex[j + 1]
            p = a[i] + fx * (a[i + 1] - a[i])
            q = b[i] + fx * (b[i + 1] - b[i])
            acc[u] += p + fy * (q - p)


def write_pictures(rig, out):
    """frames/<k>.png for each frame and images.csv; progress on stderr (a second a frame at 1080p)."""
    scene = Scene(rig, rig.seed)
    os.makedirs(os.path.join(out, 'frames'), exist_ok=True)
    with open(os.path.join(out, 'images.csv'), 'w') as f:
        f.write('frame,file\n')
        n = rig.frames()
        for k in range(n):
            name = f'frames/{k:06d}.png'
            png(os.path.join(out, name), scene.w, scene.h, scene.render(k))
            f.write(f'{k},{name}\n')
            if k % 30 == 29 or k == n - 1:
                print(f'rendered {k + 1}/{n} frames', file=sys.stderr, flush=True)


def tracker_errors(rig, matches_csv, every=5):
    """A tracker's matches (recording-v1's matches.csv) against the rig's truth (where frame_b sees
    the direction frame_a saw at (ua, va): Rig.seen_in), every `every`-th:
    (count, median error (u, v), robust spread (u, v) as 1.4826 x the median absolute deviation,
    scale (u, v): the error's share of the flow, sum(e d) / sum(d^2) over errors under 0.5 px)."""
    eu, ev, su, sv, du2, dv2 = [], [], 0.0, 0.0, 0.0, 0.0
    with open(matches_csv) as f:
        for k, r in enumerate(csv.DictReader(f)):
            if k % every:
                continue
            ua, va, ub, vb = (float(r[c]) for c in ('ua', 'va', 'ub', 'vb'))
            fa = int(r['frame_a'])
            tu, tv = rig.seen_in(int(r['frame_b']), mat_vec(rig.r_camera(rig.motion_time(fa, va)), rig.ray(ua, va)),
                                 va, False)
            eu.append(ub - tu)
            ev.append(vb - tv)
            if abs(eu[-1]) < 0.5 and abs(ev[-1]) < 0.5:  # a lost track's error is not a scale's
                du, dv = tu - ua, tv - va
                su, sv, du2, dv2 = su + eu[-1] * du, sv + ev[-1] * dv, du2 + du * du, dv2 + dv * dv
    med = statistics.median

    def spread(x):
        m = med(x)
        return 1.4826 * med([abs(a - m) for a in x])
    return len(eu), (med(eu), med(ev)), (spread(eu), spread(ev)), (su / du2, sv / dv2)
