#!/usr/bin/env python3
"""Write two Mitsuba 3 .vol grids (version 3, float32) for the heterogeneous-medium comparison:
DIR/blob_density.vol, 1 channel, 24^3: three overlapping Gaussian blobs (peak ~1, down to 0 at
the faces: a density with structure along every axis); DIR/blob_albedo.vol, 3 channels, 8^3:
an albedo that varies linearly from (0.95, 0.5, 0.2) to (0.3, 0.7, 0.98) across x, y and z.
Standard library only.   usage: make_blob_vol.py DIR"""
import math, os, struct, sys

def write_vol(path, n, channels, value):
    with open(path, 'wb') as f:
        f.write(b'VOL' + bytes([3]) + struct.pack('<iiiii', 1, n, n, n, channels) + struct.pack('<6f', 0, 0, 0, 1, 1, 1))
        for k in range(n):
            for j in range(n):
                for i in range(n):
                    p = ((i + 0.5) / n, (j + 0.5) / n, (k + 0.5) / n)
                    f.write(struct.pack('<%df' % channels, *value(p)))

def density(p):
    blobs = [((0.35, 0.4, 0.5), 0.18, 1.0), ((0.65, 0.6, 0.4), 0.15, 0.8), ((0.5, 0.3, 0.7), 0.1, 0.6)]
    d = sum(a * math.exp(-sum((p[c] - m[c]) ** 2 for c in range(3)) / (2 * s * s)) for m, s, a in blobs)
    return (min(d, 1.0),)

def albedo(p):
    t = (p[0] + p[1] + p[2]) / 3
    return tuple(a + (b - a) * t for a, b in zip((0.95, 0.5, 0.2), (0.3, 0.7, 0.98)))

out = sys.argv[1]
write_vol(os.path.join(out, 'blob_density.vol'), 24, 1, density)
write_vol(os.path.join(out, 'blob_albedo.vol'), 8, 3, albedo)
