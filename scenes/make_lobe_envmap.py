#!/usr/bin/env python3
"""Writes a latitude-longitude environment map (uncompressed scanline OpenEXR, float R, G, B)
that is a smooth lobe around the map's pole, Mitsuba's local +y (row 0):

    L(theta) = BASE + PEAK * exp((cos(theta) - 1) / WIDTH^2)      (~ exp(-theta^2 / 2 WIDTH^2))

    python3 scenes/make_lobe_envmap.py [PATH] [--base B] [--peak P] [--width RADIANS]
                                       [--columns W] [--rows H]

Defaults: bench/gpis_varying_env.exr (bench/gpis_varying.xml, which turns the pole to world +z
with its to_world): base 0.2, peak 3, width 0.35 rad (20 degrees), 8 x 180 texels (the map does
not depend on the longitude; one degree of latitude per row). A lobe without edges lights every
roughness smoothly, and a path that escapes always finds it: realization-based renderers without
light sampling (gpis vertices are delta reflections) stay low-noise under it."""
import argparse
import math
import struct

parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
parser.add_argument("path", nargs="?", default="bench/gpis_varying_env.exr")
parser.add_argument("--base", type=float, default=0.2)
parser.add_argument("--peak", type=float, default=3.0)
parser.add_argument("--width", type=float, default=0.35, help="lobe width in radians")
parser.add_argument("--columns", type=int, default=8)
parser.add_argument("--rows", type=int, default=180)
args = parser.parse_args()
if not (args.base >= 0 and args.peak >= 0 and args.width > 0 and args.columns >= 1 and args.rows >= 2):
    parser.error("need BASE, PEAK >= 0, WIDTH > 0, COLUMNS >= 1, ROWS >= 2")


def attribute(name, kind, value):
    return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(value)) + value


w, h = args.columns, args.rows
# Channels in the alphabetical order EXR requires: pixel type 2 = FLOAT, linear 0, sampling 1 1.
channels = b"".join(c + b"\0" + struct.pack("<iB3xii", 2, 0, 1, 1) for c in (b"B", b"G", b"R")) + b"\0"
window = struct.pack("<4i", 0, 0, w - 1, h - 1)
header = b"".join([
    attribute("channels", "chlist", channels),
    attribute("compression", "compression", b"\0"),  # none
    attribute("dataWindow", "box2i", window),
    attribute("displayWindow", "box2i", window),
    attribute("lineOrder", "lineOrder", b"\0"),  # increasing y
    attribute("pixelAspectRatio", "float", struct.pack("<f", 1)),
    attribute("screenWindowCenter", "v2f", struct.pack("<2f", 0, 0)),
    attribute("screenWindowWidth", "float", struct.pack("<f", 1)),
]) + b"\0"
prefix = struct.pack("<ii", 20000630, 2) + header  # magic, version 2 (single-part scanline)
line_bytes = 8 + 3 * 4 * w  # y, data size, then each channel's row
first = len(prefix) + 8 * h
offsets = struct.pack("<%dQ" % h, *[first + y * line_bytes for y in range(h)])
lines = []
for y in range(h):
    theta = math.pi * (y + 0.5) / h  # texel centre; row 0 is the pole
    value = args.base + args.peak * math.exp((math.cos(theta) - 1) / args.width ** 2)
    row = struct.pack("<%df" % w, *[value] * w)
    lines.append(struct.pack("<ii", y, 3 * 4 * w) + row * 3)
with open(args.path, "wb") as f:
    f.write(prefix + offsets + b"".join(lines))
