"""python3 -m macrofacet_mitsuba enclosure MESH OUT.ply --sigma S [--shell-extent K] [--scale A]
[--cell-size C]: writes the boundary of a macrofacet medium whose mean surface is MESH (see
enclosure.py)."""
import argparse
import sys

from .enclosure import write_enclosure


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python3 -m macrofacet_mitsuba")
    sub = ap.add_subparsers(dest="command", required=True)
    enc = sub.add_parser("enclosure", help="write the boundary (a closed PLY mesh around f < k sigma) of a mesh mean surface")
    enc.add_argument("mesh", help="the mean surface: an .obj, .ply or .serialized file")
    enc.add_argument("out", help="the PLY file to write")
    enc.add_argument("--sigma", type=float, required=True, help="the medium's sigma (scene units)")
    enc.add_argument("--shell-extent", type=float, default=3.0, help="the medium's shell_extent k (3)")
    enc.add_argument("--scale", type=float, default=1.0,
                     help="the uniform scale of the mean surface's to_world (the enclosure is in the file's units)")
    enc.add_argument("--cell-size", type=float, default=0.0,
                     help="grid cell in scene units (0: the mesh's own faces moved out when that verifies, else cells of 1/128 of its largest extent)")
    a = ap.parse_args(argv)
    try:
        n = write_enclosure(a.mesh, a.out, a.sigma, a.shell_extent, a.scale, a.cell_size)
    except (OSError, ValueError, RuntimeError) as e:
        print(f"macrofacet_mitsuba: error: {e}", file=sys.stderr)
        return 1
    print(f"{a.out}: {n} triangles around f < {a.shell_extent * a.sigma:g} (scene units)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
