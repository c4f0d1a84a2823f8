#!/usr/bin/env python3
"""Write DIR/bumps_normalmap.png for the normalmap comparison: 32x32 8-bit RGB, the tangent-space
normals (x, y, z) -> (x + 1) / 2 of the height field h = 0.08 sin(4 pi u) sin(2 pi v) (bumps
tilted by up to ~35 degrees in both directions, so both tangent axes matter). Standard library
only.   usage: make_normal_png.py DIR"""
import math, os, struct, sys, zlib

def chunk(kind, data):
    return struct.pack('>I', len(data)) + kind + data + struct.pack('>I', zlib.crc32(kind + data) & 0xffffffff)

def normal(u, v):
    dhdu = 0.08 * 4 * math.pi * math.cos(4 * math.pi * u) * math.sin(2 * math.pi * v)
    dhdv = 0.08 * 2 * math.pi * math.sin(4 * math.pi * u) * math.cos(2 * math.pi * v)
    n = (-dhdu, -dhdv, 1.0)
    l = math.sqrt(sum(c * c for c in n))
    return [n[c] / l for c in range(3)]

size = 32
rows = b''
for j in range(size):
    rows += b'\0'  # filter type none
    for i in range(size):
        n = normal((i + 0.5) / size, (j + 0.5) / size)
        rows += bytes(max(0, min(255, round((c + 1) / 2 * 255))) for c in n)
png = b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', size, size, 8, 2, 0, 0, 0)) + chunk(b'IDAT', zlib.compress(rows)) + chunk(b'IEND', b'')
with open(os.path.join(sys.argv[1], 'bumps_normalmap.png'), 'wb') as f:
    f.write(png)
