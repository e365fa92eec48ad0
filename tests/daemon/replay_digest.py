#!/usr/bin/env python3
"""The daemon's output on a reference log, byte for byte.

Replays LOG through `rsd --replay LOG --speed fast --record OUT` and hashes (SHA-256) the
payloads of the rectified images and frame infos in OUT, in order, with their channel names;
event timestamps (wall clock) are left out. Passes when the hash equals EXPECTED.

tests/data/reference-sim-96x72.lcmlog: 8 frames of the simulated camera (96 x 72, default
motion) and their velocity, recorded by rsd before the refactor of issue 12; EXPECTED was what
that rsd published for them, unchanged through the refactor, then updated once on purpose
(rows rectified with the gyro integrated across the readout). A change to the rectifier's
numbers changes the hash: then check the change, and update the expected hash in
tests/daemon/CMakeLists.txt with a reason.

Usage: replay_digest.py RSD LOG OUT EXPECTED
"""
import hashlib
import struct
import subprocess
import sys

SYNC = 0xEDA1DA01
CHANNELS = ("RSD_RECT", "RSD_FRAME_INFO")


def events(path):
    """(channel, payload) of every event of an LCM log (the format of lcm's eventlog.h)."""
    data = open(path, "rb").read()
    i = 0
    while i + 28 <= len(data):
        sync, _num, _utime, clen, dlen = struct.unpack(">IqqII", data[i:i + 28])
        if sync != SYNC:
            sys.exit(f"{path}: bad sync word at byte {i}")
        i += 28
        channel = data[i:i + clen].decode()
        i += clen
        yield channel, data[i:i + dlen]
        i += dlen


def main():
    rsd, log, out, expected = sys.argv[1:5]
    subprocess.run([rsd, "--quiet", "--replay", log, "--speed", "fast", "--record", out], check=True)
    digest = hashlib.sha256()
    counts = {c: 0 for c in CHANNELS}
    for channel, payload in events(out):
        if channel in CHANNELS:
            counts[channel] += 1
            digest.update(channel.encode())
            digest.update(payload)
    print(f"{counts}; sha256 {digest.hexdigest()}")
    if digest.hexdigest() != expected:
        sys.exit(f"output digest differs from the reference {expected}")


main()
