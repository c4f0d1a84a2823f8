#!/usr/bin/env python3
"""Write DIR/attribute_sphere.ply for the mesh_attribute comparison: a coarse UV sphere (10 x 6, ascii
PLY, triangles: Mitsuba's PLY reader takes no other polygons) whose vertices carry float r, g, b (red, green and blue
in turn, so that every triangle interpolates three different colours) and whose faces carry float r, g, b (a checker of two colours over the face
index), which Mitsuba reads as vertex_color and face_color. Standard library only.
usage: make_attribute_ply.py DIR"""
import math, os, sys

rings, segments = 6, 10
verts, faces = [], []
for i in range(rings + 1):
    th = math.pi * i / rings
    for j in range(segments):
        ph = 2 * math.pi * j / segments
        p = (math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th))
        verts.append(p + ((0.9, 0.1, 0.1), (0.1, 0.8, 0.1), (0.1, 0.2, 0.9))[(i + 2 * j) % 3])
for i in range(rings):
    for j in range(segments):
        a, b = i * segments + j, i * segments + (j + 1) % segments
        c, d = a + segments, b + segments
        col = (0.9, 0.3, 0.1) if (i + j) % 2 == 0 else (0.1, 0.4, 0.8)
        if i == 0: faces.append(((a, c, d), col))        # the pole rows: triangles
        elif i == rings - 1: faces.append(((a, c, b), col))
        else: faces += [((a, c, d), col), ((a, d, b), col)]  # a quad as two triangles of one colour
with open(os.path.join(sys.argv[1], 'attribute_sphere.ply'), 'w') as f:
    f.write('ply\nformat ascii 1.0\nelement vertex %d\n' % len(verts))
    f.write(''.join('property float %s\n' % n for n in ('x', 'y', 'z', 'r', 'g', 'b')))
    f.write('element face %d\nproperty list uchar int vertex_indices\n' % len(faces))
    f.write(''.join('property float %s\n' % n for n in ('r', 'g', 'b')))
    f.write('end_header\n')
    for v in verts: f.write('%.6f %.6f %.6f %.6f %.6f %.6f\n' % v)
    for idx, col in faces: f.write('%d %s %.3f %.3f %.3f\n' % (len(idx), ' '.join(map(str, idx)), *col))
