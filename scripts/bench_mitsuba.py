#!/usr/bin/env python3
"""Times Mitsuba 3.9.1 (scalar_rgb) on bench/anchor.xml with the thin gold shell as a macrofacet
medium (the plugin, anchor_macrofacet_mitsuba.xml) and as Mitsuba's own roughconductor
(anchor_roughconductor.xml), and the same shell with its sigma varying in space
(anchor_macrofacet_mitsuba_varying.xml, issue 12), equal resolution and spp, in one process; prints
the times and their ratios. Scene loading is not timed; each render is preceded by a small warm-up render.
usage: bench_mitsuba.py RES SPP   (needs macrofacet_mitsuba on PYTHONPATH)"""
import os
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    res, spp = sys.argv[1], sys.argv[2]
    try:
        import mitsuba as mi
        import macrofacet_mitsuba  # noqa: F401
    except ImportError as e:
        print(f"skipped: {e} (MF_SETUP_MITSUBA=1 scripts/setup.sh, then build with CMake)")
        return 0
    mi.set_variant("scalar_rgb")
    scene_file = os.path.join(ROOT, "bench", "anchor.xml")
    times = {}
    for obj in ("roughconductor", "macrofacet_mitsuba", "macrofacet_mitsuba_varying"):
        mi.render(mi.load_file(scene_file, object=obj, res="32", spp="4"))  # warm-up
        scene = mi.load_file(scene_file, object=obj, res=res, spp=spp)
        start = time.perf_counter()
        mi.render(scene, seed=1)
        times[obj] = time.perf_counter() - start
    ratio = times["macrofacet_mitsuba"] / times["roughconductor"]
    print(f"Mitsuba scalar_rgb, bench/anchor.xml {res}x{res} at {spp} spp: roughconductor {times['roughconductor']:.2f} s, "
          f"macrofacet plugin (thin shell) {times['macrofacet_mitsuba']:.2f} s: ratio {ratio:.2f}x")
    varying = times["macrofacet_mitsuba_varying"] / times["macrofacet_mitsuba"]
    print(f"Mitsuba scalar_rgb, the thin shell with sigma varying in space (a gridvolume): {times['macrofacet_mitsuba_varying']:.2f} s, "
          f"{varying:.2f}x the stationary shell (target <= 1.5x)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
