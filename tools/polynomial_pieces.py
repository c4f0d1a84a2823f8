"""What tools/erfcx_table.py and tools/normal_table.py share: the Chebyshev interpolant of one
piece, special.rs's `estrin` in Python floats, and a table of pieces as a Rust array. Needs only
mpmath (tested with mpmath 1.3.0); the scripts set its precision (40 digits)."""

from mpmath import mp, mpf


def interpolant(fn, a, b, degree):
    """The interpolant of `fn` on `[a, b]` at its `degree + 1` Chebyshev nodes, as f64
    coefficients of powers of `z` in `[-1, 1]` (lowest first), computed at mpmath's precision."""
    nodes = [mp.cos(mp.pi * (k + mpf(1) / 2) / (degree + 1)) for k in range(degree + 1)]
    values = [fn((a + b) / 2 + (b - a) / 2 * z) for z in nodes]
    vandermonde = mp.matrix([[z ** j for j in range(degree + 1)] for z in nodes])
    coefficients = mp.lu_solve(vandermonde, mp.matrix(values))
    return [float(coefficients[j]) for j in range(degree + 1)]


def estrin(c, z):
    """special.rs's `estrin`, operation for operation (Python floats are f64; Rust does not fuse
    `a * b + c`)."""
    z2 = z * z
    z4 = z2 * z2
    z8 = z4 * z4
    p01, p23, p45, p67, p89 = c[0] + c[1] * z, c[2] + c[3] * z, c[4] + c[5] * z, c[6] + c[7] * z, c[8] + c[9] * z
    p03, p47, p8a = p01 + p23 * z2, p45 + p67 * z2, p89 + c[10] * z2
    return (p03 + p47 * z4) + p8a * z8


def largest_error(coefficients, want, check):
    """The largest relative error of the f64 evaluation of a piece (`estrin`) at `check + 1`
    equally spaced `z` in `[-1, 1]` against `want(z)` (mpmath), where that is not None."""
    worst = 0.0
    for k in range(check + 1):
        z = -1 + 2 * mpf(k) / check
        value = want(z)
        if value is not None:
            worst = max(worst, float(abs((estrin(coefficients, float(z)) - value) / value)))
    return worst


def rust_array(name, pieces):
    """The lines of `pub(super) const NAME: [[f64; n]; m]` holding `pieces` (shortest round-trip
    literals: the f64 values exactly)."""
    lines = [f"pub(super) const {name}: [[f64; {len(pieces[0])}]; {len(pieces)}] = ["]
    for coefficients in pieces:
        lines.append("    [")
        lines.extend(f"        {c!r}," for c in coefficients)
        lines.append("    ],")
    lines.append("];")
    return lines
