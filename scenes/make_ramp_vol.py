#!/usr/bin/env python3
"""Writes a Mitsuba 3 .vol grid (VOL version 3, float32, one channel) over the unit cube whose
values rise geometrically from LO to HI along one axis: SAMPLES ramp values, then PAD samples
beyond each end that stay within 0.1 % per sample of the end values (so that a grid larger than
the ramp is nearly constant beyond it), one sample across the other two axes.

The padding keeps rising (falling below LO) by 0.1 % per sample instead of repeating the end
value: mfrender interpolates grids in float, and over a flat run of samples the weights' rounding
can put a value one ulp beyond the run's value, i.e. beyond the range the grid reports as its
bound, which the gpis medium refuses ("exceeds its sigma_max") and the macrofacet tracker counts
as a majorant violation. With a strictly monotone grid whose end samples lie outside the medium's
region, every bound the region sees has a sample 0.1 % beyond the values it bounds.

    python3 scenes/make_ramp_vol.py [PATH [LO HI]] [--axis x|y|z] [--samples N] [--pad P]

Defaults: scenes/sigma_ramp.vol from 0.001 to 0.05 along x, 16 samples, no padding: the height
deviation sigma of scenes/varying.xml (a polished surface to a fuzzy volume).
bench/sigma_ramp_thin.vol is 0.0008 to 0.0012 (the thin shell of bench/anchor_torus_varying.xml).
bench/gpis_varying_sigma.vol and bench/gpis_varying_lengthscale.vol (bench/gpis_varying.xml) are
    python3 scenes/make_ramp_vol.py bench/gpis_varying_sigma.vol 0.003 0.05 --samples 11 --pad 3
    python3 scenes/make_ramp_vol.py bench/gpis_varying_lengthscale.vol 0.04 0.25 --axis y --samples 11 --pad 3
Grid samples sit at cell centres (Mitsuba's gridvolume): with N + 2P cells over the unit cube,
ramp sample i is at (P + i + 1/2) / (N + 2P)."""
import argparse
import struct

parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
parser.add_argument("path", nargs="?", default="scenes/sigma_ramp.vol")
parser.add_argument("lo", nargs="?", type=float, default=0.001)
parser.add_argument("hi", nargs="?", type=float, default=0.05)
parser.add_argument("--axis", choices="xyz", default="x")
parser.add_argument("--samples", type=int, default=16, help="ramp samples (>= 2)")
parser.add_argument("--pad", type=int, default=0, help="constant samples before and after the ramp")
args = parser.parse_args()
if args.samples < 2 or args.pad < 0 or not (0 < args.lo and 0 < args.hi):
    parser.error("need --samples >= 2, --pad >= 0 and LO, HI > 0 (a geometric ramp)")

n = args.samples
ramp = [args.lo * (args.hi / args.lo) ** (i / (n - 1)) for i in range(n)]
step = 1e-3  # see the docstring: strictly monotone padding
values = [args.lo * (1 - step) ** (args.pad - k) for k in range(args.pad)] + ramp
values += [args.hi * (1 + step) ** (k + 1) for k in range(args.pad)]
shape = [1, 1, 1]
shape["xyz".index(args.axis)] = len(values)
channels = 1
data = b"VOL" + bytes([3]) + struct.pack("<i", 1) + struct.pack("<4i", *shape, channels)
data += struct.pack("<6f", 0, 0, 0, 1, 1, 1) + struct.pack("<%df" % len(values), *values)
with open(args.path, "wb") as f:
    f.write(data)
