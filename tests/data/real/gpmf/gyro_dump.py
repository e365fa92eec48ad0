#!/usr/bin/env python3
"""Prints the gyro streams of GPMF payloads: SCAL, ORIN, STMP, the sample count and the first and
last samples as raw integers. A decoder of GoPro's published KLV layout written apart from
formats/gpmf.cpp, so that tests/formats/test_gpmf.cpp checks the reader against another path.
    python3 gyro_dump.py PAYLOAD.raw ...
"""
import struct
import sys


def items(b, lo, hi):
    at = lo
    while at + 8 <= hi:
        key = b[at:at + 4]
        if key == b"\0\0\0\0":
            return
        typ, size, repeat = b[at + 4], b[at + 5], struct.unpack(">H", b[at + 6:at + 8])[0]
        n = size * repeat
        yield key.decode("ascii"), typ, size, repeat, b[at + 8:at + 8 + n]
        if typ == 0:
            yield from items(b, at + 8, at + 8 + n)
        at += 8 + ((n + 3) & ~3)


for name in sys.argv[1:]:
    b = open(name, "rb").read()
    for key, typ, size, repeat, data in items(b, 0, len(b)):
        if key in ("SCAL", "STMP", "ORIN") or key == "GYRO":
            print(name, key, chr(typ) if typ else 0, size, repeat, end=" ")
            if key == "GYRO":
                v = struct.unpack(">" + "h" * (len(data) // 2), data)
                print("first", v[:3], "last", v[-3:])
            elif chr(typ) == "c":
                print(data.split(b"\0")[0].decode())
            else:
                print(data.hex())
