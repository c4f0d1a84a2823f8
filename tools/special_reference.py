#!/usr/bin/env python3
"""Reference values for `src/special.rs`, computed with mpmath at 50 significant digits.

Writes `crates/macrofacet/tests/data/special_reference.csv`, read by `crates/macrofacet/tests/special_functions.rs`.

Regenerate (deterministic; needs only mpmath, tested with mpmath 1.3.0):

    python3 tools/special_reference.py            # from the repository root
    python3 tools/special_reference.py OUT.csv    # elsewhere

CSV columns: `function,x,want`.
- `x` is the argument as the shortest decimal string that round-trips to the `f64` actually
  used (Python `repr`), so Rust's `str::parse::<f64>` recovers exactly the double that mpmath
  evaluated at (the conversion to mpf is exact).
- `want` is the mpmath value rounded to the nearest `f64` (again as a round-trip `repr`),
  `inf`/`-inf` where it overflows. Values below the normal range are written as the nearest
  subnormal / zero; the test compares those with an absolute tolerance.

Functions (mpmath definitions, independent of the Rust algorithms):
- erf, erfc: `mp.erf`, `mp.erfc`.
- erfcx: `exp(x^2) erfc(x)`; for x >= 1e4 the asymptotic series
  `1/(x sqrt(pi)) * sum_k (-1)^k (2k-1)!!/(2x^2)^k` (mpmath's erfc cannot take such arguments;
  the series converges to 50 digits there, and both are cross-checked at x = 1e3, 1e4).
- normal_cdf: `erfc(-x/sqrt 2)/2`.
- ln_normal_cdf: `log(ncdf(x))` for x <= 0, `log1p(-ncdf(-x))` for x > 0, asymptotic series
  `-x^2/2 - log(-x) - log(sqrt(2 pi)) + log(sum_k (-1)^k (2k-1)!!/x^(2k))` for x <= -1e4.
- normal_pdf_over_cdf: `exp(ln npdf(x) - ln ncdf(x))` with the same ln ncdf; for x <= -1e4
  `-x / sum_k (-1)^k (2k-1)!!/x^(2k)` (the log difference would cancel).
- probit, probit_of_ln: the root of `ln Phi(x) = ln p` by Newton's method at 70 digits (ln Phi
  is increasing and concave, so Newton converges monotonically after the first step); the
  upper half uses `probit(p) = -probit(1-p)` with `1-p` formed exactly.
"""

import os
import sys

from mpmath import mp, mpf

mp.dps = 50

ASYMPTOTIC_X = mpf(10) ** 4


def asym_sum(z2, terms=60):
    """sum_k (-1)^k (2k-1)!! / z2^k for large z2 (z2 = 2x^2 for erfcx, x^2 for ln Phi)."""
    total = mpf(1)
    term = mpf(1)
    for k in range(1, terms):
        term = -term * (2 * k - 1) / z2
        total += term
        if abs(term) < mpf(10) ** (-mp.dps - 5):
            break
    return total


def erfcx(x):
    x = mpf(x)
    if x >= ASYMPTOTIC_X:
        return asym_sum(2 * x * x) / (x * mp.sqrt(mp.pi))
    return mp.exp(x * x) * mp.erfc(x)


def ln_ncdf(x):
    x = mpf(x)
    if x <= -ASYMPTOTIC_X:
        return -x * x / 2 - mp.log(-x) - mp.log(mp.sqrt(2 * mp.pi)) + mp.log(asym_sum(x * x))
    if x <= 0:
        return mp.log(mp.ncdf(x))
    return mp.log1p(-mp.ncdf(-x))


def ln_npdf(x):
    x = mpf(x)
    return -x * x / 2 - mp.log(mp.sqrt(2 * mp.pi))


def pdf_over_cdf(x):
    """phi(x)/Phi(x); for x <= -1e4 as -x / sum_k (-1)^k (2k-1)!!/x^(2k) (no cancellation)."""
    x = mpf(x)
    if x <= -ASYMPTOTIC_X:
        return -x / asym_sum(x * x)
    return mp.exp(ln_npdf(x) - ln_ncdf(x))


def lower_quantile_of_ln(ln_q):
    """x <= 0 with ln Phi(x) = ln_q, ln_q <= ln(1/2)."""
    # Extra digits for |ln_q| >> 1: ln Phi(x) - ln_q cancels about log10|ln_q| digits.
    extra = int(mp.log10(max(mpf(1), abs(mpf(ln_q)))))
    with mp.workdps(70 + extra):
        ln_q = mpf(ln_q)
        x = -mp.sqrt(-2 * ln_q) if ln_q < -2 else mpf(0)
        for _ in range(500):
            ln_phi = ln_ncdf(x)
            rho = pdf_over_cdf(x)
            dx = (ln_phi - ln_q) / rho
            x -= dx
            if abs(dx) <= mpf(10) ** -65 * max(1, abs(x)):
                break
        else:
            raise RuntimeError("Newton did not converge for ln_q = %s" % ln_q)
        return +x


def probit(p):
    p = mpf(p)
    if p == mpf(1) / 2:
        return mpf(0)  # exact; Newton would leave ~1e-52 of noise here
    if p <= mpf(1) / 2:
        return lower_quantile_of_ln(mp.log(p))
    return -lower_quantile_of_ln(mp.log(1 - p))


def probit_of_ln(ln_p):
    ln_p = mpf(ln_p)
    if ln_p > -mp.log(2):
        return -lower_quantile_of_ln(mp.log(-mp.expm1(ln_p)))
    return lower_quantile_of_ln(ln_p)


def f64(v):
    """Nearest double of an mpf, as a round-trip string."""
    d = float(v)  # mpmath rounds to nearest
    return repr(d)


def linspace(a, b, n):
    return [a + (b - a) * i / (n - 1) for i in range(n)]


def logspace(e0, e1, n, sign=1.0):
    return [sign * 10.0 ** (e0 + (e1 - e0) * i / (n - 1)) for i in range(n)]


def uniq(xs):
    seen = set()
    out = []
    for x in xs:
        x = float(x)
        if x not in seen:
            seen.add(x)
            out.append(x)
    return sorted(out)


def self_checks():
    # Series and direct formula agree where both are valid.
    for x in (mpf(1000), mpf(10000)):
        direct = mp.exp(x * x) * mp.erfc(x)
        series = asym_sum(2 * x * x) / (x * mp.sqrt(mp.pi))
        assert abs(direct / series - 1) < mpf(10) ** -45, (x, direct, series)
        direct = mp.log(mp.ncdf(-x))
        series = -x * x / 2 - mp.log(x) - mp.log(mp.sqrt(2 * mp.pi)) + mp.log(asym_sum(x * x))
        assert abs(direct / series - 1) < mpf(10) ** -45, (x, direct, series)
    # The quantile really inverts Phi.
    for p in (mpf("1e-300"), mpf("0.3"), mpf("0.5"), mpf("0.975")):
        x = probit(p)
        assert abs(mp.ncdf(x) - p) <= mpf(10) ** -45 * p, (p, x)


def main():
    self_checks()
    rows = []

    def add(name, xs, fn):
        for x in uniq(xs):
            rows.append((name, repr(x), f64(fn(x))))

    # erf / erfc over [-6, 27] with tiny arguments.
    tiny = [1e-300, -1e-300, 1e-100, 1e-10, -1e-10, 1e-5, 3e-3]
    add("erf", linspace(-6.0, 6.0, 49) + tiny + [0.1, 0.3, 0.84375, 1.25, 2.857, 27.0],
        lambda x: mp.erf(x))
    add("erfc", linspace(-6.0, 27.0, 67) + tiny + [0.1, 0.3, 0.84375, 1.25, 2.857, 26.5, 27.2],
        lambda x: mp.erfc(x))

    # erfcx over [-26, 1e300]: dense in [-5, 30], log-spaced beyond.
    add("erfcx", linspace(-5.0, 30.0, 71) + [-26.0, -20.0, -10.0, 25.99, 26.0, 26.01, 1e-300, 1e-8]
        + logspace(1.5, 8, 14) + [1e12, 1e50, 1e154, 1e200, 1e300], erfcx)

    # normal_pdf over [-38, 38].
    add("normal_pdf", linspace(-38.0, 38.0, 39) + [1e-10, 0.5, -1.5, 7.25],
        lambda x: mp.npdf(x))

    # normal_cdf over [-37, 8].
    add("normal_cdf", linspace(-37.0, 8.0, 46) + [-36.5, -1.0, -0.999, -1e-8, 1e-8, -0.3, 0.3, 2.5],
        lambda x: mp.ncdf(x))

    # ln_normal_cdf over [-1e6, 40], dense in [-50, 10].
    add("ln_normal_cdf", linspace(-50.0, 10.0, 121) + logspace(2, 6, 9, -1.0)
        + [12.0, 15.0, 20.0, 30.0, 37.0, 38.0, 40.0, -1e-10, 1e-10, 1e-300],
        lambda x: ln_ncdf(x))

    # normal_pdf_over_cdf over [-1e6, 40].
    add("normal_pdf_over_cdf", linspace(-50.0, 10.0, 61) + logspace(2, 6, 9, -1.0)
        + [12.0, 20.0, 30.0, 37.0, 38.0, 40.0, -1e-10, 1e-10, 1e154, -1e154],
        lambda x: pdf_over_cdf(x) if x < 100 else mpf(0))  # underflows for x > 38.6

    # probit over [1e-300, 1 - 1e-16]: dense near both tails and 0.5; plus subnormal p.
    ps = (logspace(-300, -1.2, 60) + linspace(0.06, 0.94, 45)
          + [0.5 + d for d in (1e-16, 1e-12, 1e-8, 1e-4, 0.01)]
          + [0.5 - d for d in (1e-16, 1e-12, 1e-8, 1e-4, 0.01)]
          + [0.5, 0.075, 0.0749, 0.925, 0.9251, 1.4e-11, 1.3e-11]
          + [1.0 - d for d in logspace(-1.5, -16, 24)]
          + [1.0 - 2.0 ** -53, 1e-310, 5e-324])
    add("probit", ps, probit)

    # probit_of_ln over ln p in [-1e300, 0).
    ls = (logspace(-18, 0, 25, -1.0) + linspace(-3.0, -0.01, 31)
          + logspace(0, 12, 40, -1.0) + [-0.6931471805599453, -0.6931471805599452, -0.6931471806,
                                           -25.0, -729.0, -730.0, -745.2, -1e20, -1e21, -1e100,
                                           -1e300])
    add("probit_of_ln", ls, probit_of_ln)

    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "crates", "macrofacet", "tests", "data", "special_reference.csv")
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    with open(out, "w", newline="\n") as fh:
        fh.write("# Generated by tools/special_reference.py (mpmath %s, %d digits); do not edit.\n"
                 % (mp.__version__ if hasattr(mp, "__version__") else __import__("mpmath").__version__,
                    mp.dps))
        fh.write("function,x,want\n")
        for name, x, want in rows:
            fh.write("%s,%s,%s\n" % (name, x, want))
    print("wrote %d rows to %s" % (len(rows), os.path.normpath(out)))


if __name__ == "__main__":
    main()
