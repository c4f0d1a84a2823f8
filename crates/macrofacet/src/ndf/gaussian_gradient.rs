//! Gradients `g ~ N((0,0,1), diag(alpha_x², alpha_y², alpha_z²) / 2)`: the gradient of a GPSS at a
//! zero crossing (seeds/000 Eq. 37, with `sigma²/l² = alpha²/2` from seeds/000 Eq. 4). Beckmann is the `alpha_z = 0`
//! case (slopes are Gaussian), the generalized macrofacet the `alpha_z > 0` case.
//!
//! Both the projected area and exact visible-normal sampling follow from the gradient-space
//! identity of the design notes: `∫ h(m) D(m) dm = E[|g| h(g/|g|)]`, hence
//! `projected_area(w) = E[max(0, w·g)]` and the visible normals from `w` are the directions of
//! `g` drawn from `N(mu, Sigma) · max(0, w·g)`. Whitening `g = mu + L z` with `L = Sigma^(1/2)`
//! reduces that density to a 1-D density `∝ (x + c)_+ φ(x)` along `L w` times an independent
//! standard normal in the orthogonal plane. This is exact importance sampling of the generalized
//! vNDF, which seeds/000 leaves as future work (it uses the mixture of seeds/000 Eq. 40).

use crate::special::{erfcx, normal_cdf, normal_pdf};
use glam::{DMat3, DVec3};
use std::f64::consts::{FRAC_1_SQRT_2, PI};

const FRAC_1_SQRT_PI: f64 = 0.564_189_583_547_756_3;

/// Beyond this, `e^{-c²/2}` underflows: no flake is visible in f64 and sampling reports `None`.
const MIN_VISIBLE_C: f64 = -38.0;

#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct GaussianGradient {
    /// The spread `L` of `g = e_z + L z`.
    pub spread: Spread,
}

/// `L` with `Cov(g) = L Lᵀ`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Spread {
    /// Frame-aligned kernels: `L = diag(alpha)/√2` with the roughnesses `alpha` (seeds/000 Eq. 4).
    Diagonal(DVec3),
    /// A full local anisotropy (seeds/004 Eqs. 25–26): `L = K/√2` with `K Kᵀ = Q`, the "α²
    /// matrix" `Q = 2 Cov(g)` (lower-triangular `K`).
    Matrix(DMat3),
}

/// `E[max(0, w·g)]` for `w·g` of mean `w_z` and `s = sqrt(2)` times its standard deviation:
/// `s (a Φ(√2 a) + φ(√2 a)/√2)` with `a = w_z / s` (seeds/000 Eq. 32's `a`), written as
/// `s (max(a, 0) + e^{−a²} (1/√π − |a| erfcx(|a|)) / 2)`: with `erfc(−a) = 2 − e^{−a²} erfcx(a)`
/// for `a ≥ 0`, one `erfcx` and one `exp` on both sides, and no cancellation for grazing-from-below
/// directions (`a < 0`, where the first term is 0). Increasing in `w_z` and in `s`.
pub(crate) fn expected_positive_part(w_z: f64, s: f64) -> f64 {
    if s == 0.0 {
        return w_z.max(0.0);
    }
    let a = w_z / s;
    if a.is_infinite() {
        // s below f64's resolution of w_z (erfcx(∞) = 0 would meet ∞): the limit s → 0.
        return w_z.max(0.0);
    }
    if a >= NO_TAIL {
        // The tail, e^{−a²}/(4 a² √π) to leading order (below 1e-18 here), is under half an ulp
        // of `a`: `a + tail` is `a` exactly, without its `exp` and `erfcx` (most of a thin
        // shell's σ_t evaluations look along the flakes' normals, where `a` is large).
        return s * a;
    }
    s * (a.max(0.0) + tail(a))
}

/// [`expected_positive_part`]'s `e^{−a²} (1/√π − |a| erfcx(|a|)) / 2`, over `s`.
#[inline]
fn tail(a: f64) -> f64 {
    0.5 * (-a * a).exp() * (FRAC_1_SQRT_PI - a.abs() * erfcx(a.abs()))
}

/// Where [`expected_positive_part`]'s tail no longer changes `a` (checked by a unit test).
const NO_TAIL: f64 = 6.0;

impl GaussianGradient {
    pub fn diagonal(alpha: DVec3) -> Self {
        GaussianGradient { spread: Spread::Diagonal(alpha) }
    }

    /// `Lᵀ w`: `w·g = w_z + (Lᵀ w)·z`.
    fn spread_t(&self, w: DVec3) -> DVec3 {
        match self.spread {
            Spread::Diagonal(alpha) => alpha * FRAC_1_SQRT_2 * w,
            Spread::Matrix(k) => k.transpose() * w * FRAC_1_SQRT_2,
        }
    }

    /// `L z`.
    fn spread(&self, z: DVec3) -> DVec3 {
        match self.spread {
            Spread::Diagonal(alpha) => alpha * FRAC_1_SQRT_2 * z,
            Spread::Matrix(k) => k * z * FRAC_1_SQRT_2,
        }
    }

    /// `s(w) = sqrt(wᵀ Q w)` (`sqrt(alpha_x² w_x² + alpha_y² w_y² + alpha_z² w_z²)` for a
    /// frame-aligned kernel), the denominator of `a` in seeds/000 Eq. 32; `sqrt(2)` times the
    /// standard deviation of `w·g`.
    fn s(&self, w: DVec3) -> f64 {
        match self.spread {
            Spread::Diagonal(alpha) => (alpha * w).length(),
            Spread::Matrix(k) => (k.transpose() * w).length(),
        }
    }

    /// `E[max(0, w·g)]`: [`expected_positive_part`] of `w_z` and `s(w)`.
    pub fn projected_area(&self, w: DVec3) -> f64 {
        expected_positive_part(w.z, self.s(w))
    }

    /// Exact sample of the visible normals from `wi`. `u[0]` drives the 1-D density along `L wi`,
    /// `u[1], u[2]` the orthogonal standard normal pair (Box–Muller).
    pub fn sample_visible(&self, wi: DVec3, u: [f64; 3]) -> Option<DVec3> {
        // Whitened coordinates: g = e_z + L z, z ~ N(0, I).
        let v = self.spread_t(wi); // wi·g = wi.z + v·z
        let v_len = v.length();
        let z = if v_len == 0.0 {
            // wi·g is the constant wi.z: every gradient is equally visible (or none is).
            if wi.z <= 0.0 {
                return None;
            }
            let (n1, n2) = box_muller(u[1], u[2]);
            let (e1, e2) = DVec3::Z.any_orthonormal_pair();
            e1 * n1 + e2 * n2 + DVec3::Z * crate::special::probit(u[0])
        } else {
            let c = wi.z / v_len;
            if c < MIN_VISIBLE_C {
                return None;
            }
            let e1 = v / v_len;
            let (e2, e3) = e1.any_orthonormal_pair();
            let x = sample_shifted_linear_gaussian(c, u[0]);
            let (n2, n3) = box_muller(u[1], u[2]);
            e1 * x + e2 * n2 + e3 * n3
        };
        let g = DVec3::Z + self.spread(z);
        let m = g.try_normalize()?;
        // Rounding can leave a sample a hair behind the visibility plane at grazing angles.
        (wi.dot(m) > 0.0).then_some(m)
    }
}

/// Two independent standard normals from two uniforms in `[0, 1)`.
pub(crate) fn box_muller(u1: f64, u2: f64) -> (f64, f64) {
    let r = (-2.0 * (-u1).ln_1p()).sqrt();
    let (sin, cos) = (2.0 * PI * u2).sin_cos();
    (r * cos, r * sin)
}

/// Inverts the CDF of the density `∝ (x + c)_+ φ(x)` at `u`.
///
/// With `Z = φ(c) + c Φ(c)`, the unnormalised CDF is
/// `F(x) = φ(c) − φ(x) + c [Φ(x) − Φ(−c)]` and the survival `S(x) = φ(x) + c Φ(−x)`; for `c < 0`
/// the survival is evaluated as `φ(x) [1 − |c| M(x)]` with the Mills ratio
/// `M(x) = Φ(−x)/φ(x) = sqrt(π/2) erfcx(x/√2)` so that nothing underflows. Halley/Newton on the
/// logarithm of whichever tail is better conditioned (`ln F` below the median for `c >= 0`,
/// `ln S` otherwise) — nearly linear in the tails, so a few steps suffice — safeguarded by
/// bisection on the bracket `[-c, max(-c, 0) + 40]`.
pub(crate) fn sample_shifted_linear_gaussian(c: f64, u: f64) -> f64 {
    let lower_tail = c >= 0.0 && u < 0.5;
    // φ(x), or e^{-(x²-c²)/2} = φ(x)/φ(c) for c < 0 (everything is divided by φ(c) there).
    let gauss = |x: f64| -> f64 {
        if c < 0.0 {
            (-(x - c) * (x + c) * 0.5).exp()
        } else {
            normal_pdf(x)
        }
    };
    let (pdf_c, cdf_minus_c) = (normal_pdf(c), normal_cdf(-c));
    // The tail at x from `e = gauss(x)`, which the step needs too (one exponential per step);
    // for c < 0 the survival S(x)/φ(c) = e^{-(x² - c²)/2} [1 − |c| M(x)] (x >= −c).
    let tail = |x: f64, e: f64| -> f64 {
        if lower_tail {
            pdf_c - e + c * (normal_cdf(x) - cdf_minus_c)
        } else if c >= 0.0 {
            e + c * normal_cdf(-x)
        } else {
            e * (1.0 + c * mills_ratio(x))
        }
    };
    // (Φ(c) = 1 − Φ(−c) for c >= 0 without cancellation: Φ(−c) <= 1/2.)
    let z = if c >= 0.0 { pdf_c + c * (1.0 - cdf_minus_c) } else { tail(-c, gauss(-c)) };
    let ln_target = if lower_tail { (u * z).ln() } else { ((-u).ln_1p()) + z.ln() };
    // h(x) = ±(ln tail(x) − ln target) is increasing, with h' = p/T and h'' = p'/T ∓ (p/T)²
    // for the density p = (x + c) φ(x), p' = φ(x) (1 − x (x + c)).
    let sign = if lower_tail { 1.0 } else { -1.0 };
    let mut lo = -c;
    let mut hi = (-c).max(0.0) + 40.0;
    let mut x = initial_guess(c, u).clamp(lo, hi);
    for _ in 0..60 {
        let e = gauss(x);
        let t = tail(x, e);
        let h = sign * (t.ln() - ln_target);
        if h.is_nan() {
            x = 0.5 * (lo + hi);
            continue;
        }
        if h < 0.0 {
            lo = x;
        } else if h > 0.0 {
            hi = x;
        } else {
            return x;
        }
        let slope = (x + c) * e / t;
        let curvature = e * (1.0 - x * (x + c)) / t - sign * slope * slope;
        // Halley's step (cubic convergence), falling back to Newton's where its correction is
        // large (far from the root).
        let newton_step = h / slope;
        let correction = 1.0 - 0.5 * newton_step * curvature / slope;
        let halley = correction > 0.5 && correction < 2.0;
        let step = if halley { newton_step / correction } else { newton_step };
        let candidate = x - step;
        // Near the root the error after a step is ~ step³ (Halley) or ~ step² (Newton): once
        // that is below 1e-15 the candidate is final without another evaluation. (It may land a
        // rounding error outside the bracket: accept it.)
        let converged = if halley { 1e-5 } else { 1e-8 };
        if step.abs() <= converged * (1.0 + x.abs()) {
            return candidate.clamp(-c, f64::MAX);
        }
        let next = if slope > 0.0 && candidate > lo && candidate < hi { candidate } else { 0.5 * (lo + hi) };
        if (next - x).abs() <= 1e-13 * (1.0 + x.abs()) {
            return next;
        }
        x = next;
    }
    x
}

/// The Mills ratio `M(x) = Φ(−x)/φ(x) = sqrt(π/2) erfcx(x/√2)`.
fn mills_ratio(x: f64) -> f64 {
    (PI / 2.0).sqrt() * erfcx(x * FRAC_1_SQRT_2)
}

/// The starting points of the quantile's table over `c ∈ [−3, 8]`, `u ∈ [0.018, 0.982]`,
/// generated by `tools/visible_slope_table.py`.
mod visible_slope_table;

/// A starting point near the quantile: inside the table's domain the table's (within ~1e-5
/// (1 + |x|), so that one Halley step is final); for very negative `c`, `x + c` tends to a
/// Gamma(2, |c|) variable; otherwise the Laplace approximation of the density about its mode
/// `x* = (−c + sqrt(c² + 4))/2` (where `1/(x + c) = x`), with variance `1/(1 + 1/(x* + c)²)`
/// (it becomes `φ(x − 1/c)` for large `c`; 2 to 4 evaluations).
fn initial_guess(c: f64, u: f64) -> f64 {
    if let Some(x) = tabulated_quantile(c, u) {
        return x;
    }
    if c < -3.0 {
        // Gamma(2, 1) quantile q: (1 + q) e^{-q} = 1 − u, by three fixed-point steps.
        let w = -(-u).ln_1p();
        let mut q = w + (1.0 + w).ln();
        q = w + (1.0 + q).ln();
        q = w + (1.0 + q).ln();
        -c + q / (-c)
    } else {
        let mode = 0.5 * ((c * c + 4.0).sqrt() - c);
        let width = 1.0 / (1.0 + 1.0 / ((mode + c) * (mode + c))).sqrt();
        (mode + width * crate::special::probit(u)).max(-c + 1e-3 * (mode + c))
    }
}

/// The quantile at `(c, u)` interpolated in the table (Catmull-Rom in `c` and in
/// `l = ln(u / (1 − u))`), or `None` outside its domain (NaN included).
fn tabulated_quantile(c: f64, u: f64) -> Option<f64> {
    use visible_slope_table::{C_MIN, C_NODES, C_STEP, L_MIN, L_NODES, L_STEP, QUANTILES};
    let (fc, fl) = ((c - C_MIN) / C_STEP, ((u / (1.0 - u)).ln() - L_MIN) / L_STEP);
    if !((0.0..=(C_NODES - 1) as f64).contains(&fc) && (0.0..=(L_NODES - 1) as f64).contains(&fl)) {
        return None;
    }
    // The interval's nodes i, i + 1 and their neighbours are rows i..i + 4 of the padded table.
    let (i, j) = ((fc as usize).min(C_NODES - 2), (fl as usize).min(L_NODES - 2));
    let (wc, wl) = (catmull_rom_weights(fc - i as f64), catmull_rom_weights(fl - j as f64));
    let mut x = 0.0;
    for (row, w) in QUANTILES[i..i + 4].iter().zip(wc) {
        let r = &row[j..j + 4];
        x += w * (wl[0] * f64::from(r[0]) + wl[1] * f64::from(r[1]) + wl[2] * f64::from(r[2]) + wl[3] * f64::from(r[3]));
    }
    Some(x)
}

/// The weights of the Catmull-Rom cubic through nodes 1 (`t = 0`) and 2 (`t = 1`) of four.
fn catmull_rom_weights(t: f64) -> [f64; 4] {
    let (t2, t3) = (t * t, t * t * t);
    [0.5 * (2.0 * t2 - t - t3), 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0), 0.5 * (4.0 * t2 + t - 3.0 * t3), 0.5 * (t3 - t2)]
}

#[cfg(test)]
mod tests {
    use super::{expected_positive_part, sample_shifted_linear_gaussian, tabulated_quantile, tail, NO_TAIL};
    use crate::rng::Pcg32;
    use crate::special::{normal_cdf, normal_pdf};

    /// Inside the table's domain its starting point lies within the `1e-5 (1 + |x|)` of the
    /// quantile below which one Halley step is final, and the sampler's result (from it, or
    /// from the analytic starting points outside) is the quantile: `F(x) / Z = u` to 1e-11.
    #[test]
    fn the_tables_starting_points_are_one_step_from_the_quantile() {
        let mut rng = Pcg32::new(11, 5);
        let (mut tabulated, mut checked) = (0, 0);
        for _ in 0..20_000 {
            let (c, u) = (-6.0 + 18.0 * rng.next_f64(), rng.next_f64());
            let x = sample_shifted_linear_gaussian(c, u);
            // The CDF of (x + c)_+ φ(x) from the side the sampler inverts (which keeps its
            // relative accuracy).
            let z = normal_pdf(c) + c * normal_cdf(c);
            let (value, target) = if c >= 0.0 && u < 0.5 {
                ((normal_pdf(c) - normal_pdf(x) + c * (normal_cdf(x) - normal_cdf(-c))) / z, u)
            } else {
                ((normal_pdf(x) + c * normal_cdf(-x)) / z, 1.0 - u)
            };
            if target > 1e-3 && c > -4.0 {
                checked += 1;
                assert!((value - target).abs() <= 1e-11 * target, "c {c}, u {u}: x {x} has F/Z {value} against {target}");
            }
            if let Some(guess) = tabulated_quantile(c, u) {
                tabulated += 1;
                assert!((guess - x).abs() <= 1e-5 * (1.0 + x.abs()), "c {c}, u {u}: the table starts at {guess}, the quantile is {x}");
            }
        }
        assert!(tabulated > 10_000 && checked > 15_000, "{tabulated} tabulated, {checked} checked");
        assert_eq!(tabulated_quantile(f64::NAN, 0.5), None);
        assert_eq!(tabulated_quantile(0.0, 0.999), None);
        assert_eq!(tabulated_quantile(8.5, 0.5), None);
    }

    /// The tail, computed as below [`NO_TAIL`], leaves `a` unchanged from there on.
    #[test]
    fn the_tail_is_below_an_ulp_beyond_no_tail() {
        let mut a = NO_TAIL;
        while a < 1e3 {
            let tail = tail(a);
            assert_eq!(a + tail, a, "a = {a}: tail {tail:e}");
            a = a * 1.001 + 1e-3;
        }
    }

    /// `E[max(0, w_z + s N/√2)]` is continuous down to `s = 0`, where it is `max(w_z, 0)`: also
    /// where `w_z / s` overflows, and it stays finite and increasing in `w_z` across `a = 0`.
    #[test]
    fn expected_positive_part_is_continuous_to_the_sharp_limit() {
        for w_z in [-0.5, -1e-300, 0.0, 1e-300, 0.5] {
            for s in [0.0, 1e-320, 1e-300] {
                let p = expected_positive_part(w_z, s);
                assert!(p.is_finite() && (p - w_z.max(0.0)).abs() <= 1e-15 * w_z.abs() + 1e-299, "w_z {w_z}, s {s}: {p}");
            }
        }
        let values: Vec<f64> = (-400..=400).map(|k| expected_positive_part(k as f64 / 100.0, 0.7)).collect();
        assert!(values.windows(2).all(|w| w[0] <= w[1] && w[0].is_finite()), "not increasing");
    }
}
