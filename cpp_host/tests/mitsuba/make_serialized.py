#!/usr/bin/env python3
"""Write a two-shape Mitsuba 'serialized' file (format version 4, zlib, with the trailing
offset dictionary) for the comparison tests: shape 0 a flat quad, shape 1 a UV torus with
vertex normals and texture coordinates. Standard library only.
usage: make_serialized.py OUT.serialized"""
import math, struct, sys, zlib

def shape(name, pos, nrm, uv, tris, single=True):
    flags = 0x1000 if single else 0x2000
    if nrm: flags |= 0x0001
    if uv: flags |= 0x0002
    f = 'f' if single else 'd'
    body = struct.pack('<I', flags) + name.encode() + b'\0' + struct.pack('<QQ', len(pos), len(tris))
    body += b''.join(struct.pack('<3' + f, *p) for p in pos)
    if nrm: body += b''.join(struct.pack('<3' + f, *n) for n in nrm)
    if uv: body += b''.join(struct.pack('<2' + f, *t) for t in uv)
    body += b''.join(struct.pack('<3I', *t) for t in tris)
    return struct.pack('<HH', 0x041C, 4) + zlib.compress(body)

def torus(R=1.0, r=0.4, nu=48, nv=24):
    pos, nrm, uv, tris = [], [], [], []
    for i in range(nu + 1):
        for j in range(nv + 1):
            u, v = 2 * math.pi * i / nu, 2 * math.pi * j / nv
            c = (math.cos(u), math.sin(u), 0.0)
            n = (math.cos(v) * c[0], math.cos(v) * c[1], math.sin(v))
            pos.append(tuple(R * c[k] + r * n[k] for k in range(3)))
            nrm.append(n)
            uv.append((i / nu, j / nv))
    w = nv + 1
    for i in range(nu):
        for j in range(nv):
            a, b, c, d = i * w + j, (i + 1) * w + j, (i + 1) * w + j + 1, i * w + j + 1
            tris += [(a, b, c), (a, c, d)]
    return pos, nrm, uv, tris

quad = shape('quad', [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], None, None, [(0, 1, 2), (0, 2, 3)])
tor = shape('torus', *torus(), single=False)
data = quad + tor + struct.pack('<QQI', 0, len(quad), 2)
with open(sys.argv[1], 'wb') as out:
    out.write(data)
