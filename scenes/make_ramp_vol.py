#!/usr/bin/env python3
"""Writes a Mitsuba 3 .vol grid (VOL version 3, float32, one channel) of 16 x 1 x 1 values over
the unit cube, rising geometrically along x from LO to HI.

    python3 scenes/make_ramp_vol.py [PATH [LO HI]]

Defaults: scenes/sigma_ramp.vol from 0.001 to 0.05, the height deviation sigma of
scenes/varying.xml (a polished surface to a fuzzy volume). bench/sigma_ramp_thin.vol is
0.0008 to 0.0012 (the thin shell of bench/anchor_torus_varying.xml)."""
import struct
import sys

nx, ny, nz, channels = 16, 1, 1, 1
lo, hi = (float(sys.argv[2]), float(sys.argv[3])) if len(sys.argv) > 3 else (0.001, 0.05)
values = [lo * (hi / lo) ** (i / (nx - 1)) for i in range(nx)]
data = b"VOL" + bytes([3]) + struct.pack("<i", 1) + struct.pack("<4i", nx, ny, nz, channels)
data += struct.pack("<6f", 0, 0, 0, 1, 1, 1) + struct.pack("<%df" % len(values), *values)
path = sys.argv[1] if len(sys.argv) > 1 else "scenes/sigma_ramp.vol"
with open(path, "wb") as f:
    f.write(data)
