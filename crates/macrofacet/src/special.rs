//! Special functions of the standard normal distribution, in `f64`, accurate over the whole
//! range a renderer reaches.
//!
//! Macrofacet theory turns a Gaussian-process surface into an exponential medium whose flake
//! density along the signed distance `f` is the inverse Mills ratio
//! `ρ(f) = φ(f)/Φ(f)` (seeds/000 Eq. 13 of the macrofacet paper, with `f` in units of `σ`):
//!
//! - [`normal_pdf_over_cdf`] evaluates `ρ` itself. Deep inside the surface (`f → −∞`) both `φ`
//!   and `Φ` underflow while `ρ(f) ≈ −f` stays perfectly ordinary, so it is built on [`erfcx`].
//! - Optical depths are integrals of `ρ`, i.e. differences of [`ln_normal_cdf`]
//!   (`d ln Φ / df = ρ`). `ln Φ` must stay relatively accurate both far below the surface
//!   (`ln Φ(−1e6) ≈ −5e11`) and far above it (`ln Φ(10) ≈ −7.6e-24`, which is `−Φ(−10)`).
//! - Free-flight sampling inverts an optical depth: it needs `Φ⁻¹` of a probability that is
//!   only known through its logarithm, [`probit_of_ln`]. [`probit`] is the plain inverse of
//!   [`normal_cdf`] (e.g. for sampling the slope NDF).
//! - [`erf`], [`erfc`], [`erfcx`], [`normal_pdf`] and [`normal_cdf`] are the building blocks and
//!   are also used by the NDF / `Λ` code.
//!
//! No function panics. A NaN argument gives NaN. Accuracies quoted below are measured against
//! 50-digit mpmath references (`tools/special_reference.py`, `tests/special_functions.rs`).
//!
//! References:
//! - M. J. Wichura, "Algorithm AS 241: The Percentage Points of the Normal Distribution",
//!   Applied Statistics 37(3), 477–484 (1988) — the `PPND16` rational approximations.
//! - Laplace's continued fraction for the complementary error function, Abramowitz & Stegun
//!   7.1.14 (see also DLMF §7.9): `√π e^{x²} erfc x = 1/(x + (1/2)/(x + 1/(x + (3/2)/(x + …))))`.
//! - The asymptotic expansion `ln Φ(x) = −x²/2 − ln(−x) − ½ln(2π) + ln(1 − 1/x² + …)`
//!   (A&S 26.2.12) for the start of the far-tail inversion.
//! - Dekker / fused multiply-add splitting of a product into an exact `hi + lo` pair.

use std::f64::consts::{FRAC_1_SQRT_2, LN_2, PI};

/// `1/√π`.
const FRAC_1_SQRT_PI: f64 = 0.564_189_583_547_756_3;
/// `1/√(2π)`.
const FRAC_1_SQRT_2PI: f64 = 0.398_942_280_401_432_7;
/// `√(2/π)`.
const SQRT_2_OVER_PI: f64 = 0.797_884_560_802_865_4;
/// `√(2π)`.
const SQRT_2PI: f64 = 2.506_628_274_631_000_7;

/// `ln 2 − LN_2` (the part of ln 2 below `f64` precision).
const LN_2_LO: f64 = 2.319_046_813_846_299_6e-17;
/// `probit_of_ln` uses AS 241's central region for `ln p ∈ [LN_CENTRAL_LO, LN_CENTRAL_HI]`,
/// just inside `p ∈ [0.075, 0.925]`.
const LN_CENTRAL_LO: f64 = -2.59;
const LN_CENTRAL_HI: f64 = -0.078;

/// Above this `erfcx` uses Laplace's continued fraction; below it `e^{x²} erfc(x)`
/// (`erfc(26) ≈ 5.7e-296` is still a normal number, `e^{676}` is finite).
const ERFCX_CF_THRESHOLD: f64 = 26.0;

/// `x²` as an exact unevaluated sum `hi + lo` ([`product_error`]). Where `x²` overflows, `lo`
/// is `−∞` (as an FMA gives it); where it underflows, `lo` is below `1e-300` and may be inexact.
#[inline]
fn square_split(x: f64) -> (f64, f64) {
    let hi = x * x;
    if !hi.is_finite() {
        return (hi, -hi);
    }
    (hi, product_error(x, x, hi))
}

/// `a b − p` for the rounded product `p = a b`, exactly (TwoProduct): one FMA where the target
/// has it, else Dekker's product of Veltkamp's 26-bit halves, bit for bit the same wherever the
/// halves' products neither overflow nor underflow (`|a b| < 1e300`, `|a b| > 1e-290`). Without
/// the `fma` target feature (x86-64's baseline) `f64::mul_add` is a call into a routine that
/// dispatches at run time: 110,000 calls per 8,192 paths of bench/gpis_compare.xml's fuzzy
/// sphere, about 5 % of its time against a build with FMA.
#[inline]
fn product_error(a: f64, b: f64, p: f64) -> f64 {
    #[cfg(target_feature = "fma")]
    {
        a.mul_add(b, -p)
    }
    #[cfg(not(target_feature = "fma"))]
    {
        let (a_hi, a_lo) = veltkamp_split(a);
        let (b_hi, b_lo) = veltkamp_split(b);
        ((a_hi * b_hi - p) + a_hi * b_lo + a_lo * b_hi) + a_lo * b_lo
    }
}

/// `a = hi + lo` with `hi` holding the upper 26 bits of `a`'s significand and `lo` the rest
/// (Veltkamp's split, `|a| < 2^996`).
#[cfg(not(target_feature = "fma"))]
#[inline]
fn veltkamp_split(a: f64) -> (f64, f64) {
    const SPLITTER: f64 = 134_217_729.0; // 2^27 + 1
    let c = SPLITTER * a;
    let hi = c - (c - a);
    (hi, a - hi)
}

/// `exp(−(hi + lo))` for the exact square `hi + lo` of [`square_split`]: `exp(−hi)·(1 − lo)`,
/// `|lo| ≤ ulp(hi)/2`, so the rounding error of `x²` does not get amplified by the exponential.
/// (When `x²` overflows, `lo` is `−∞`; the result is then 0, not NaN.)
#[inline]
fn exp_neg_split(hi: f64, lo: f64) -> f64 {
    let e = (-hi).exp();
    if e == 0.0 {
        0.0
    } else {
        e * (1.0 - lo)
    }
}

/// `exp(hi + lo)` for the exact square `hi + lo` of [`square_split`], `+∞` on overflow.
#[inline]
fn exp_pos_split(hi: f64, lo: f64) -> f64 {
    let e = hi.exp();
    if e.is_infinite() {
        e
    } else {
        e * (1.0 + lo)
    }
}

/// Error function `erf(x)`, all `x`: the C library's (C99 `erf`, about 1 ulp).
#[inline]
pub fn erf(x: f64) -> f64 {
    // SAFETY: C99 erf is a pure function of a double, defined for every input.
    unsafe { c_math::erf(x) }
}

/// Complementary error function `erfc(x) = 1 − erf(x)`, all `x`: the C library's (C99 `erfc`,
/// about 1 ulp), relatively accurate until it underflows near `x ≈ 27.2`.
#[inline]
pub fn erfc(x: f64) -> f64 {
    // SAFETY: C99 erfc is a pure function of a double, defined for every input.
    unsafe { c_math::erfc(x) }
}

/// The C99 error functions of the platform's C library (which `std` already links for `exp`,
/// `ln`, ...): in a profile of `bench/anchor.xml`'s thin shell the portable `libm` crate's `erfc`
/// took 12.6 % of the time, glibc's 3.9 %.
mod c_math {
    extern "C" {
        pub fn erf(x: f64) -> f64;
        pub fn erfc(x: f64) -> f64;
    }
}

/// Scaled complementary error function `erfcx(x) = e^{x²} erfc(x)`.
///
/// - `x ≥ 26`: Laplace's continued fraction (A&S 7.1.14), `≈ 1/(x√π)`; never underflows
///   spuriously (`erfcx(1e300) = 5.6e-301`, `erfcx(+∞) = 0`).
/// - `0 ≤ x < 26`: polynomial pieces in `y = 4/(4 + x)` ([`erfcx_pieces`]), which the tracker's
///   flake density and `ln Φ` call several times per tentative collision. Against
///   `e^{x²} erfc(x)` from the C library (an `exp` and an `erfc`), and with the projected area's
///   `expected_positive_part` using it, the thin shell of bench/anchor.xml renders with 3.4 %
///   fewer instructions.
/// - `x < 0`: `2 e^{x²} − erfcx(−x)` (no cancellation: the first term is ≥ 2, the second ≤ 1),
///   with `x²` split exactly into `hi + lo` and `e^{x²} = e^{hi}(1 + lo)`.
///   Finite for `x ≥ −26.6`; below that the true value exceeds `f64::MAX` and `+∞` is returned
///   (`erfcx(−∞) = +∞`).
///
/// Relative error measured ≲ 1e-15 on `[−26, 1e300]`; ≤ 4.1e-16 at 22,000 points of `[0, 26)`
/// and 3.9e-16 at 2,000 of `[−26, 0)` (against mpmath).
pub fn erfcx(x: f64) -> f64 {
    if x.is_nan() {
        return f64::NAN;
    }
    if x >= ERFCX_CF_THRESHOLD {
        return erfcx_continued_fraction(x);
    }
    if x >= 0.0 {
        erfcx_pieces(x)
    } else {
        // For x < −26.64 exp(hi) overflows to +∞, which is the correctly rounded answer.
        let (hi, lo) = square_split(x);
        2.0 * exp_pos_split(hi, lo) - erfcx(-x)
    }
}

/// The polynomial pieces of `erfcx` on `[0, 26)`, generated by `tools/erfcx_table.py`.
mod erfcx_table;

/// `erfcx(x)` for `0 ≤ x < 26`: the piece of [`erfcx_table`] that `y = 4/(4 + x)` falls in,
/// a Chebyshev interpolant of degree 10 (3.9e-16 relative in f64, the script's check).
/// `y` carries its own rounding as a correction: `4 + x` is formed as an exact sum `s + e`
/// (TwoSum), and `4/(s + e) = y + δ` with `δ = (4 − y s − y e) y/4` (the remainder exactly,
/// [`product_error`]).
/// Uncorrected, the rounding of `y` alone is worth up to 1e-15 relative near `x = 0`.
#[inline]
fn erfcx_pieces(x: f64) -> f64 {
    use erfcx_table::{COEFFICIENTS, FIRST, PIECES, SCALE};
    let s = SCALE + x;
    let x_part = s - SCALE;
    let e = (SCALE - (s - x_part)) + (x - x_part);
    let y = SCALE / s;
    // The remainder 4 − y s is a float (a division's remainder), and 4 − fl(y s) is exact
    // (Sterbenz: y s ≈ 4): so it is (4 − fl(y s)) − (y s − fl(y s)), without rounding.
    let ys = y * s;
    let delta = (((SCALE - ys) - product_error(y, s, ys)) - y * e) * (y / SCALE);
    // y ∈ (2/15, 1] for x ∈ [0, 26): pieces FIRST..PIECES (the clamp only guards the table).
    let scaled = PIECES * y;
    let i = (scaled as usize).clamp(FIRST, PIECES as usize - 1);
    let z = (2.0 * (scaled - i as f64) - 1.0) + 2.0 * PIECES * delta;
    estrin(&COEFFICIENTS[i - FIRST], z)
}

/// `Σ c_k z^k` for the 11 coefficients of a piece by Estrin's scheme: pairs, then pairs of
/// pairs with `z²`, `z⁴`, `z⁸` (half the dependent steps of Horner's rule).
#[inline]
fn estrin(c: &[f64; 11], z: f64) -> f64 {
    let z2 = z * z;
    let z4 = z2 * z2;
    let z8 = z4 * z4;
    let p01 = c[0] + c[1] * z;
    let p23 = c[2] + c[3] * z;
    let p45 = c[4] + c[5] * z;
    let p67 = c[6] + c[7] * z;
    let p89 = c[8] + c[9] * z;
    let p03 = p01 + p23 * z2;
    let p47 = p45 + p67 * z2;
    let p8a = p89 + c[10] * z2;
    (p03 + p47 * z4) + p8a * z8
}

/// Laplace's continued fraction for `erfcx`, evaluated bottom-up with a depth that falls as `x`
/// grows (each level gains a factor of about `2x²`). The depths were chosen against 40-digit
/// mpmath values on 3,000 points per range: the largest relative error is 2.1e-16 on each range,
/// as with 16 levels everywhere, at a third to a sixteenth of the divisions.
#[inline]
fn erfcx_continued_fraction(x: f64) -> f64 {
    let depth = if x < 70.0 {
        6.0
    } else if x < 2e3 {
        4.0
    } else if x < 1e5 {
        2.0
    } else {
        1.0
    };
    let mut t = x;
    let mut k = depth;
    while k >= 1.0 {
        t = x + 0.5 * k / t;
        k -= 1.0;
    }
    // (1/√π)/t rather than 1/(√π t): stays a correct subnormal for x near f64::MAX.
    FRAC_1_SQRT_PI / t
}

/// The polynomial pieces of `ln Φ` and `φ/Φ` on `[−8, 3)`, generated by `tools/normal_table.py`.
mod normal_table;

/// The piece of [`normal_table`] that `x` falls in and its local variable `z ∈ [−1, 1]`, or
/// `None` outside `[X_LO, X_HI)` (and for NaN). `x − X_LO` is formed as an exact sum `s + e`
/// (TwoSum) and `e` carried into `z`: its rounding alone would be worth up to 2e-15 absolute in
/// `x`, 3e-14 relative in `ln Φ` near 0.
#[inline]
fn normal_piece(x: f64) -> Option<(usize, f64)> {
    use normal_table::{LN_CDF, PER_UNIT, X_HI, X_LO};
    if !(X_LO..X_HI).contains(&x) {
        return None;
    }
    let s = x - X_LO;
    let x_part = s + X_LO;
    let e = (x - x_part) + (-X_LO - (s - x_part));
    // PER_UNIT is a power of two: `scaled` is exact, and so is `scaled − i`.
    let scaled = PER_UNIT * s;
    let i = (scaled as usize).min(LN_CDF.len() - 1);
    Some((i, (2.0 * (scaled - i as f64) - 1.0) + 2.0 * PER_UNIT * e))
}

/// Standard normal density `φ(x) = e^{−x²/2}/√(2π)`, all `x`.
///
/// `x²` is split exactly so the result is relatively accurate (≲ 2 ulp) until it underflows
/// (`|x| ≳ 38.6`). `φ(±∞) = 0`.
#[inline]
pub fn normal_pdf(x: f64) -> f64 {
    if x.is_infinite() {
        return 0.0;
    }
    let (hi, lo) = square_split(x);
    FRAC_1_SQRT_2PI * exp_neg_split(0.5 * hi, 0.5 * lo)
}

/// Standard normal distribution function `Φ(x)`, all `x`.
///
/// Relatively accurate (measured ≲ 1e-15) in the lower tail until it underflows
/// (`Φ(−37) ≈ 5.7e-300`, subnormal below `x ≈ −37.5`, zero below `x ≈ −38.5`).
/// For `x < −1` it is formed as `½ e^{−x²/2} erfcx(−x/√2)` with `x²` split exactly, so the
/// rounding of `x/√2` is not amplified; otherwise `½ erfc(−x/√2)`.
/// `Φ(−∞) = 0`, `Φ(+∞) = 1`.
#[inline]
pub fn normal_cdf(x: f64) -> f64 {
    if x < -1.0 {
        if x == f64::NEG_INFINITY {
            return 0.0;
        }
        let (hi, lo) = square_split(x);
        0.5 * exp_neg_split(0.5 * hi, 0.5 * lo) * erfcx(-x * FRAC_1_SQRT_2)
    } else {
        0.5 * erfc(-x * FRAC_1_SQRT_2)
    }
}

/// `ln Φ(x)`, all `x`; relative error measured ≲ 1e-15.
///
/// - `−8 ≤ x < 3` (a shell's heights `f/σ`, where the tracker asks at every segment): the
///   polynomial piece of [`normal_table`] (3.8e-16 relative, the script's check) instead of an
///   `erfcx` and a logarithm (the tracker's inversion went from 517 to 357 instructions a call
///   on bench/anchor.xml's torus).
/// - `x < 0`: `−x²/2 + ln(erfcx(−x/√2)/2)` — both terms negative, no cancellation, no underflow;
///   behaves like `−x²/2 − ln(−x) − ln√(2π)` as `x → −∞`. Returns `−∞` only when `x²/2`
///   itself overflows (`x < −1.34e154`; the true value is then below `−f64::MAX`) or at `x = −∞`.
/// - `x ≥ 0`: `log1p(−Φ(−x))`, relatively accurate while `Φ(−x)` is a normal number
///   (`ln Φ(10) ≈ −7.62e-24`); for `x ≳ 37.5` it is a subnormal or `−0.0`
///   (the true value `−Φ(−x)` is below `f64`'s range). `ln Φ(+∞) = 0`.
pub fn ln_normal_cdf(x: f64) -> f64 {
    match normal_piece(x) {
        Some((i, z)) => estrin(&normal_table::LN_CDF[i], z),
        None => ln_normal_cdf_closed_form(x),
    }
}

/// [`ln_normal_cdf`] outside the table.
fn ln_normal_cdf_closed_form(x: f64) -> f64 {
    if x.is_nan() {
        return f64::NAN;
    }
    if x < 0.0 {
        if x == f64::NEG_INFINITY {
            return f64::NEG_INFINITY;
        }
        -0.5 * (x * x) + (0.5 * erfcx(-x * FRAC_1_SQRT_2)).ln()
    } else {
        (-normal_cdf(-x)).ln_1p()
    }
}

/// Inverse Mills ratio `φ(x)/Φ(x)` — the macrofacet flake density `ρ` (seeds/000 Eq. 13), all `x`.
///
/// `−8 ≤ x < 3`: the polynomial piece of [`normal_table`] (4.4e-16 relative). Elsewhere
/// `x < 0`: `√(2/π)/erfcx(−x/√2)`, which behaves like `−x` as `x → −∞` and never forms
/// `0/0`; `x ≥ 0`: `φ(x)/Φ(x)` directly (`Φ ≥ ½`). Relative error measured ≲ 1e-15 for
/// `x ∈ [−1e300, 38]`; it underflows to 0 above `x ≈ 38.6`.
/// `ρ(−∞) = +∞`, `ρ(+∞) = 0`.
#[inline]
pub fn normal_pdf_over_cdf(x: f64) -> f64 {
    match normal_piece(x) {
        Some((i, z)) => estrin(&normal_table::PDF_OVER_CDF[i], z),
        None => normal_pdf_over_cdf_closed_form(x),
    }
}

/// [`normal_pdf_over_cdf`] outside the table.
#[inline]
fn normal_pdf_over_cdf_closed_form(x: f64) -> f64 {
    if x < 0.0 {
        SQRT_2_OVER_PI / erfcx(-x * FRAC_1_SQRT_2)
    } else {
        // NaN also takes this branch and stays NaN.
        normal_pdf(x) / normal_cdf(x)
    }
}

// ---------------------------------------------------------------------------------------------
// Inverse: Wichura's PPND16 (AS 241, 1988) + one refinement step.
// ---------------------------------------------------------------------------------------------

/// Evaluates `num(r)/den(r)` for degree-7 polynomials, coefficients in ascending order
/// (`den[0]` is 1 in all of AS 241's tables).
#[inline]
fn rational7(num: &[f64; 8], den: &[f64; 8], r: f64) -> f64 {
    let mut n = num[7];
    let mut d = den[7];
    for i in (0..7).rev() {
        n = n * r + num[i];
        d = d * r + den[i];
    }
    n / d
}

/// AS 241 central region, `|q| ≤ 0.425` with `q = p − ½`: returns `Φ⁻¹(½ + q)`.
// Coefficients exactly as printed by Wichura (1988), more digits than f64 holds.
#[allow(clippy::excessive_precision)]
#[inline]
fn ppnd16_central(q: f64) -> f64 {
    const A: [f64; 8] = [
        3.387_132_872_796_366_608,
        1.331_416_678_917_843_774_5e2,
        1.971_590_950_306_551_442_7e3,
        1.373_169_376_550_946_112_5e4,
        4.592_195_393_154_987_145_7e4,
        6.726_577_092_700_870_085_3e4,
        3.343_057_558_358_812_810_5e4,
        2.509_080_928_730_122_672_7e3,
    ];
    const B: [f64; 8] = [
        1.0,
        4.231_333_070_160_091_125_2e1,
        6.871_870_074_920_579_083e2,
        5.394_196_021_424_751_107_7e3,
        2.121_379_430_158_659_586_7e4,
        3.930_789_580_009_271_061e4,
        2.872_908_573_572_194_267_4e4,
        5.226_495_278_852_854_561e3,
    ];
    let r = 0.180_625 - q * q;
    q * rational7(&A, &B, r)
}

/// AS 241 tail regions: given `r = √(−ln p)` for a lower-tail probability `p < 0.075`, returns
/// `−Φ⁻¹(p) > 0`. Wichura's tables cover `r ≤ 27` (`p ≳ 1e-316`); beyond that (only reached
/// through [`probit_of_ln`]) the asymptotic inversion [`tail_asymptotic`] is used.
// Coefficients exactly as printed by Wichura (1988), more digits than f64 holds.
#[allow(clippy::excessive_precision)]
#[inline]
fn ppnd16_tail(r: f64) -> f64 {
    const C: [f64; 8] = [
        1.423_437_110_749_683_577_34,
        4.630_337_846_156_545_295_9,
        5.769_497_221_460_691_405_5,
        3.647_848_324_763_204_605_04,
        1.270_458_252_452_368_382_58,
        2.417_807_251_774_506_117_7e-1,
        2.272_384_498_926_918_458_33e-2,
        7.745_450_142_783_414_076_4e-4,
    ];
    const D: [f64; 8] = [
        1.0,
        2.053_191_626_637_758_821_87,
        1.676_384_830_183_803_849_4,
        6.897_673_349_851_000_045_5e-1,
        1.481_039_764_274_800_745_9e-1,
        1.519_866_656_361_645_719_66e-2,
        5.475_938_084_995_344_946e-4,
        1.050_750_071_644_416_843_24e-9,
    ];
    const E: [f64; 8] = [
        6.657_904_643_501_103_777_2,
        5.463_784_911_164_114_369_9,
        1.784_826_539_917_291_335_8,
        2.965_605_718_285_048_912_3e-1,
        2.653_218_952_657_612_309_3e-2,
        1.242_660_947_388_078_438_6e-3,
        2.711_555_568_743_487_578_15e-5,
        2.010_334_399_292_288_132_65e-7,
    ];
    const F: [f64; 8] = [
        1.0,
        5.998_322_065_558_879_376_9e-1,
        1.369_298_809_227_358_053_1e-1,
        1.487_536_129_085_061_485_25e-2,
        7.868_691_311_456_132_591e-4,
        1.846_318_317_510_054_681_8e-5,
        1.421_511_758_316_445_888_7e-7,
        2.044_263_103_389_939_785_64e-15,
    ];
    if r <= 5.0 {
        rational7(&C, &D, r - 1.6)
    } else if r <= 27.0 {
        rational7(&E, &F, r - 5.0)
    } else {
        tail_asymptotic(r * r)
    }
}

/// `−Φ⁻¹(p)` for `m = −ln p ≥ 729` from the asymptotic expansion of `ln Φ` (A&S 26.2.12):
/// with `y = x²`, `y = 2m − ln(2π y) − 2/y + O(1/y²)`; one fixed-point step from
/// `y₀ = 2m − ln(4π m)` leaves a relative error `O(ln(y)²/y³)` (< 1e-8 at `m = 729`,
/// < 1e-30 at `m = 1e10`). Written so that nothing overflows for `m` up to `f64::MAX`.
#[inline]
fn tail_asymptotic(m: f64) -> f64 {
    let ln_4pi = (4.0 * PI).ln();
    let half_y0 = m - 0.5 * (ln_4pi + m.ln());
    let ln_2pi_y0 = ln_4pi + half_y0.ln();
    let half_y1 = m - 0.5 * ln_2pi_y0 - 0.5 / half_y0;
    2.0_f64.sqrt() * half_y1.sqrt()
}

/// Quantile of the standard normal distribution, `Φ⁻¹(p)`.
///
/// `p = 0 → −∞`, `p = 1 → +∞`, `p` NaN or outside `[0, 1]` → NaN. Wichura's AS 241 (PPND16)
/// followed by one Halley step on `Φ(x) = p` (with `Φ(x) − ½ = ½ erf(x/√2)` in the central
/// region so small results keep their relative accuracy; with `Φ` from [`normal_cdf`] in the
/// tails, mirrored through the exact `1 − p` for `p > ½`). Below `p = 1e-290` the refinement
/// is done in log space by [`probit_of_ln`] (subnormal `p` has few significant bits).
/// Relative error measured ≲ 1e-15 for `p ∈ [1e-300, 1 − 2⁻⁵³]` (subnormal `p` included).
pub fn probit(p: f64) -> f64 {
    if p.is_nan() || !(0.0..=1.0).contains(&p) {
        return f64::NAN;
    }
    if p == 0.0 {
        return f64::NEG_INFINITY;
    }
    if p == 1.0 {
        return f64::INFINITY;
    }
    let q = p - 0.5; // exact for p ∈ [1/4, 1], and below ¼ within ½ ulp of p
    if q.abs() <= 0.425 {
        return probit_central(q);
    }
    // Tail: work with the lower-tail probability pl = min(p, 1 − p) (1 − p is exact here).
    // `lower` is Φ⁻¹(pl) ≤ 0; the result is `lower` for p < ½ and `−lower` for p > ½.
    let (pl, mirror) = if q < 0.0 { (p, 1.0) } else { (1.0 - p, -1.0) };
    let lower = if pl < 1e-290 {
        // Φ(x) would be (nearly) subnormal: refine on ln Φ instead.
        probit_of_ln(pl.ln())
    } else {
        let x = -ppnd16_tail((-pl.ln()).sqrt());
        halley_step(x, normal_cdf(x) - pl)
    };
    mirror * lower
}

/// `Φ⁻¹(½ + q)` for `|q| ≤ 0.425`: AS 241's central approximation and one Halley step on
/// `g(x) = (Φ(x) − ½) − q` with `Φ(x) − ½ = ½ erf(x/√2)`, so that the residual — and hence the
/// result — stays relatively accurate for tiny `q`.
#[inline]
fn probit_central(q: f64) -> f64 {
    let x = ppnd16_central(q);
    halley_step(x, 0.5 * erf(x * FRAC_1_SQRT_2) - q)
}

/// One Halley step for `Φ(x) = p` given the residual `e = Φ(x) − p`:
/// `u = e/φ(x)`, `x ← x − u/(1 + x u/2)` (since `φ' = −x φ`).
#[inline]
fn halley_step(x: f64, e: f64) -> f64 {
    // e^{x²/2} = 1/(√(2π) φ(x)).
    let (hi, lo) = square_split(x);
    let u = e * SQRT_2PI * exp_pos_split(0.5 * hi, 0.5 * lo);
    if !u.is_finite() {
        return x;
    }
    x - u / (1.0 + 0.5 * x * u)
}

/// `Φ⁻¹(e^{ln_p})` — the normal quantile of a probability given by its logarithm.
///
/// Valid for `ln_p ≤ 0` with full accuracy even where `e^{ln_p}` underflows: measured relative
/// error ≲ 1e-15 for `ln_p ∈ [−1e300, 0)`. `ln_p = 0 → +∞`, `ln_p = −∞ → −∞`, `ln_p > 0` or
/// NaN → NaN.
///
/// - `p > 0.925`: `−Φ⁻¹(q)` with `q = 1 − p = −expm1(ln_p)` computed accurately.
/// - `0.075 ≤ p ≤ 0.925`: AS 241's central region with `p − ½ = ½ expm1(ln_p + ln 2)` (ln 2 to
///   double-double precision, so the result near `ln_p = −ln 2` is relatively accurate) and the
///   same Halley step as [`probit`].
/// - `p < 0.075`: AS 241 with the tail variable `r = √(−ln_p)` taken directly from `ln_p`
///   (and the asymptotic inversion beyond AS 241's range `r > 27`, then three Newton steps in
///   log space, `x ← x − (ln Φ(x) − ln_p)/ρ(x)` with `ρ = φ/Φ = d ln Φ/dx`). Within its range
///   AS 241 from the exact `r` needs no step: 4.2e-16 at worst over the mpmath references (2.9e-16
///   with one), and one would move it by at most 8.7e-16 relative over 2·10⁶ points of
///   `[−729, ln 0.075]`; a step costs more than the approximation, and a free flight inverts
///   here whenever it collides below −1.44σ. For `ln_p < −1e20` the
///   asymptotic start is already exact to far below an ulp and is returned as is (this keeps
///   `x²` from overflowing for `ln_p` near `−f64::MAX`).
pub fn probit_of_ln(ln_p: f64) -> f64 {
    if ln_p.is_nan() || ln_p > 0.0 {
        return f64::NAN;
    }
    if ln_p == 0.0 {
        return f64::INFINITY;
    }
    if ln_p == f64::NEG_INFINITY {
        return f64::NEG_INFINITY;
    }
    if ln_p > LN_CENTRAL_HI {
        // p > 0.925: mirror through q = 1 − p = −expm1(ln_p), accurate however small.
        return -probit(-ln_p.exp_m1());
    }
    if ln_p >= LN_CENTRAL_LO {
        // 0.075 < p ≤ 0.925: q = p − ½ = ½ expm1(ln_p + ln 2) with ln 2 in two parts, so q
        // (and the result near 0) keeps its relative accuracy as ln_p → −ln 2.
        let d = (ln_p + LN_2) + LN_2_LO;
        return probit_central(0.5 * d.exp_m1());
    }
    let m = -ln_p;
    if m > 1e20 {
        return -tail_asymptotic(m);
    }
    let mut x = -ppnd16_tail(m.sqrt());
    // Newton in log space from the asymptotic start only: AS 241 is already within ~2 ulps.
    let steps = if m > 729.0 { 3 } else { 0 };
    for _ in 0..steps {
        let step = (ln_normal_cdf(x) - ln_p) / normal_pdf_over_cdf(x);
        if !step.is_finite() {
            break;
        }
        x -= step;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn smoke() {
        assert!((erfcx(0.0) - 1.0).abs() < 1e-16);
        assert!((normal_cdf(0.0) - 0.5).abs() < 1e-16);
        assert!(probit(0.5).abs() < 1e-16);
        assert!((probit(0.975) - 1.959_963_984_540_054).abs() < 1e-14);
        assert!(probit_of_ln(-LN_2).abs() < 1e-15);
    }

    /// The table's pieces agree with the closed forms they replace on `[−8, 3)` (both within
    /// ~4e-16 of mpmath: tools/normal_table.py's check, special.rs's docs), at 200,000 points,
    /// the pieces' ends among them.
    #[test]
    fn table_pieces_agree_with_the_closed_forms() {
        use normal_table::{LN_CDF, PER_UNIT, X_HI, X_LO};
        let mut worst = [0.0f64; 2];
        let ends = (0..=LN_CDF.len()).map(|i| X_LO + i as f64 / PER_UNIT).flat_map(|x: f64| [x, f64::from_bits(x.to_bits() - 1), f64::from_bits(x.to_bits() + 1)]);
        for x in (0..200_000).map(|i| X_LO + (X_HI - X_LO) * (i as f64 + 0.5) / 200_000.0).chain(ends).filter(|x| (X_LO..X_HI).contains(x)) {
            let pairs = [(ln_normal_cdf(x), ln_normal_cdf_closed_form(x)), (normal_pdf_over_cdf(x), normal_pdf_over_cdf_closed_form(x))];
            for (k, (table, closed)) in pairs.into_iter().enumerate() {
                worst[k] = worst[k].max(((table - closed) / closed).abs());
            }
        }
        assert!(worst[0] < 1.5e-15 && worst[1] < 1.5e-15, "largest relative differences: ln Φ {:e}, φ/Φ {:e}", worst[0], worst[1]);
    }

    /// Dekker's product (the build without FMA) gives the FMA's exact error bit for bit over
    /// the range the module uses it in: random significands at exponents from 2^-400 to 2^400,
    /// both signs, and `erfcx`'s division remainders.
    #[test]
    fn product_error_is_the_exact_rounding_error() {
        let mut rng = crate::rng::Pcg32::new(7, 11);
        let mut random = || {
            let significand = 1.0 + rng.next_f64();
            let exponent = (rng.next_u32() % 801) as i32 - 400;
            let sign = if rng.next_u32() % 2 == 0 { 1.0 } else { -1.0 };
            sign * significand * 2f64.powi(exponent)
        };
        for _ in 0..100_000 {
            let (a, b) = (random(), random());
            let p = a * b;
            assert_eq!(product_error(a, b, p).to_bits(), a.mul_add(b, -p).to_bits(), "{a:e} × {b:e}");
            let (hi, lo) = square_split(a);
            assert_eq!((hi.to_bits(), lo.to_bits()), ((a * a).to_bits(), a.mul_add(a, -hi).to_bits()), "{a:e}²");
        }
        for x in [0.0, 1e-300, 0.1, 0.5, 1.0, 3.7, 12.0, 25.999] {
            let s = 4.0 + x;
            let y = 4.0 / s;
            let ys = y * s;
            assert_eq!(((4.0 - ys) - product_error(y, s, ys)).to_bits(), (-y).mul_add(s, 4.0).to_bits(), "x = {x}");
        }
        // x² beyond f64's range: the error is −∞, as with an FMA.
        assert_eq!(square_split(1e200), (f64::INFINITY, f64::NEG_INFINITY));
    }
}
