//! Statistical machinery for validating samplers (in the spirit of Mitsuba 3's `chi2` module).
//!
//! Pure maths, no I/O. Everything here exists so that tests can check that a sampler draws
//! from the density it claims:
//!
//! - [`Pcg32`]: a small deterministic generator (O'Neill's PCG32) for tests and validation.
//!   The rendering API itself owns no RNG; callers pass uniform numbers.
//! - Special functions for p-values: the regularized incomplete gamma functions
//!   [`gamma_p`] / [`gamma_q`], the chi-square survival function [`chi2_sf`] and the
//!   Kolmogorov survival function [`kolmogorov_sf`].
//! - [`sidak_alpha`]: the Šidák correction for running several tests at one family-wise level.
//! - [`SphereChi2`]: Pearson chi-square goodness of fit of a direction sampler against its
//!   pdf (solid-angle measure) over the whole unit sphere, with cell pooling; [`chi2_1d`] for
//!   scalar samplers on an interval; [`chi2_counts`] for already-binned data.
//! - [`ks_test`]: one-sample Kolmogorov–Smirnov test (atoms in the cdf are handled).
//! - [`mean_and_standard_error`]: Welford's running mean and standard error, for furnace
//!   tests.
//!
//! ## Typical use
//! ```
//! use glam::DVec3;
//! use macrofacet_validation::stats::{sidak_alpha, Pcg32, SphereChi2};
//! use std::f64::consts::PI;
//!
//! // Level of each test when a file runs 4 of them at a family-wise level of 1%.
//! let alpha = sidak_alpha(0.01, 4);
//! let sample_uniform_sphere = |r: &mut Pcg32| {
//!     let (z, phi) = (1.0 - 2.0 * r.next_f64(), 2.0 * PI * r.next_f64());
//!     let s = (1.0 - z * z).sqrt();
//!     Some(DVec3::new(s * phi.cos(), s * phi.sin(), z))
//! };
//! let test = SphereChi2 { samples: 20_000, ..SphereChi2::default() };
//! let outcome = test.run(|_| 1.0 / (4.0 * PI), sample_uniform_sphere, &mut Pcg32::new(7, 1));
//! assert!(outcome.passes(alpha), "{outcome}");
//! ```

use core::f64::consts::PI;
use core::fmt;
use glam::DVec3;

pub use macrofacet::rng::Pcg32;

// ---------------------------------------------------------------------------------------------
// Special functions
// ---------------------------------------------------------------------------------------------

const EPS: f64 = 1e-16;
const MAX_ITERATIONS: usize = 100_000;

/// `ln(1 + t) − t`, accurate also for small `|t|` (where the naive form cancels).
fn log1p_minus(t: f64) -> f64 {
    if t.abs() <= 0.5 {
        // ln(1+t) = 2 atanh(y), y = t/(2+t); 2y − t = −t²/(2+t).
        let y = t / (2.0 + t);
        let y2 = y * y;
        let mut power = y * y2;
        let mut sum = 0.0;
        let mut k = 3.0;
        loop {
            let term = power / k;
            sum += term;
            if term.abs() <= EPS * sum.abs() {
                break;
            }
            power *= y2;
            k += 2.0;
        }
        -t * t / (2.0 + t) + 2.0 * sum
    } else {
        libm::log1p(t) - t
    }
}

/// Stirling's series remainder `ln Γ(a) − [(a − ½) ln a − a + ½ ln 2π]` for `a ≥ 10`
/// (Abramowitz–Stegun 6.1.41, truncation error below 1e-15 there).
fn stirling_remainder(a: f64) -> f64 {
    let r = 1.0 / a;
    let r2 = r * r;
    r * (1.0 / 12.0
        - r2 * (1.0 / 360.0
            - r2 * (1.0 / 1260.0 - r2 * (1.0 / 1680.0 - r2 * (1.0 / 1188.0 - r2 * (691.0 / 360_360.0))))))
}

/// `ln(xᵃ e⁻ˣ / Γ(a))`, the common prefactor of the series and the continued fraction.
/// For `a ≥ 10` it is written as `a·(ln(1+t) − t) + ½ ln(a/2π) − stirling(a)` with
/// `x = a(1 + t)`, which avoids the cancellation of `a ln x − x − ln Γ(a)` (Temme / Loader).
fn ln_gamma_prefactor(a: f64, x: f64) -> f64 {
    if a >= 10.0 {
        let t = (x - a) / a;
        a * log1p_minus(t) + 0.5 * (a / (2.0 * PI)).ln() - stirling_remainder(a)
    } else {
        a * x.ln() - x - libm::lgamma(a)
    }
}

/// Series `P(a,x) = xᵃe⁻ˣ/Γ(a) · Σₙ xⁿ / (a(a+1)…(a+n))` (Numerical Recipes §6.2, A&S 6.5.29);
/// used for `x < a + 1`.
fn gamma_p_series(a: f64, x: f64) -> f64 {
    let mut term = 1.0 / a;
    let mut sum = term;
    let mut ap = a;
    for _ in 0..MAX_ITERATIONS {
        ap += 1.0;
        term *= x / ap;
        sum += term;
        if term.abs() < sum.abs() * EPS {
            break;
        }
    }
    sum * ln_gamma_prefactor(a, x).exp()
}

/// Continued fraction `Q(a,x) = xᵃe⁻ˣ/Γ(a) · 1/(x+1−a− 1(1−a)/(x+3−a− 2(2−a)/(x+5−a− …)))`
/// (Numerical Recipes §6.2, A&S 6.5.31) evaluated with the modified Lentz method; used for
/// `x ≥ a + 1`.
fn gamma_q_continued_fraction(a: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let mut b = x + 1.0 - a;
    let mut c = 1.0 / TINY;
    let mut d = 1.0 / b;
    let mut h = d;
    for i in 1..MAX_ITERATIONS {
        let i = i as f64;
        let an = -i * (i - a);
        b += 2.0;
        d = an * d + b;
        if d.abs() < TINY {
            d = TINY;
        }
        c = b + an / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        let delta = d * c;
        h *= delta;
        if (delta - 1.0).abs() < EPS {
            break;
        }
    }
    h * ln_gamma_prefactor(a, x).exp()
}

/// Regularized lower incomplete gamma function `P(a, x) = γ(a, x) / Γ(a)`, `a > 0`, `x ≥ 0`.
///
/// Series for `x < a + 1`, Lentz continued fraction for the complement otherwise (Numerical
/// Recipes 3rd ed. §6.2; Abramowitz–Stegun 6.5.29 and 6.5.31). Relative accuracy about 1e-12
/// or better for `a ≥ ½`. Returns NaN for `a ≤ 0`, `x < 0` or NaN arguments.
#[must_use]
pub fn gamma_p(a: f64, x: f64) -> f64 {
    if a.is_nan() || x.is_nan() || a <= 0.0 || x < 0.0 || a == f64::INFINITY {
        return f64::NAN;
    }
    if x == 0.0 {
        0.0
    } else if x == f64::INFINITY {
        1.0
    } else if x < a + 1.0 {
        gamma_p_series(a, x)
    } else {
        1.0 - gamma_q_continued_fraction(a, x)
    }
}

/// Regularized upper incomplete gamma function `Q(a, x) = Γ(a, x) / Γ(a) = 1 − P(a, x)`,
/// `a > 0`, `x ≥ 0`.
///
/// The upper tail is computed directly by the continued fraction for `x ≥ a + 1`, so tiny
/// tail probabilities keep their relative accuracy (about 1e-12 or better for `a ≥ ½`).
/// Returns NaN for `a ≤ 0`, `x < 0` or NaN arguments.
#[must_use]
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if a.is_nan() || x.is_nan() || a <= 0.0 || x < 0.0 || a == f64::INFINITY {
        return f64::NAN;
    }
    if x == 0.0 {
        1.0
    } else if x == f64::INFINITY {
        0.0
    } else if x < a + 1.0 {
        1.0 - gamma_p_series(a, x)
    } else {
        gamma_q_continued_fraction(a, x)
    }
}

/// Chi-square survival function (p-value) `P(X ≥ stat)` for `X ~ χ²(dof)`:
/// `Q(dof/2, stat/2)`.
///
/// `dof = 0` is the point mass at 0: the result is 1 for `stat ≤ 0` and 0 otherwise. A
/// negative `stat` gives 1, `+∞` gives 0, NaN gives NaN.
#[must_use]
pub fn chi2_sf(stat: f64, dof: usize) -> f64 {
    if stat.is_nan() {
        return f64::NAN;
    }
    if stat <= 0.0 {
        return 1.0;
    }
    if dof == 0 {
        return 0.0;
    }
    gamma_q(0.5 * dof as f64, 0.5 * stat)
}

/// Survival function of the Kolmogorov distribution,
/// `Q_KS(λ) = 2 Σ_{j≥1} (−1)^{j−1} e^{−2j²λ²}` (the limiting law of `√n·D_n`).
///
/// For `λ < 1.18` the equivalent Jacobi-theta form
/// `1 − (√(2π)/λ) Σ_{j≥1} e^{−(2j−1)²π²/(8λ²)}` is used, which converges fast there
/// (Numerical Recipes 3rd ed. §6.14). Returns 1 for `λ ≤ 0`, NaN for NaN.
#[must_use]
pub fn kolmogorov_sf(lambda: f64) -> f64 {
    if lambda.is_nan() {
        return f64::NAN;
    }
    if lambda <= 0.0 {
        return 1.0;
    }
    if lambda < 1.18 {
        let w = PI * PI / (8.0 * lambda * lambda);
        let mut sum = 0.0;
        for j in 1..MAX_ITERATIONS {
            let k = (2 * j - 1) as f64;
            let term = (-k * k * w).exp();
            sum += term;
            if term <= EPS * sum {
                break;
            }
        }
        (1.0 - (2.0 * PI).sqrt() / lambda * sum).clamp(0.0, 1.0)
    } else {
        let l2 = lambda * lambda;
        let mut sum = 0.0;
        let mut sign = 1.0;
        for j in 1..MAX_ITERATIONS {
            let j = j as f64;
            let term = (-2.0 * j * j * l2).exp();
            sum += sign * term;
            if term <= EPS * sum.abs() {
                break;
            }
            sign = -sign;
        }
        (2.0 * sum).clamp(0.0, 1.0)
    }
}

/// Šidák-corrected per-test significance level: running `n_tests` independent tests each at
/// `1 − (1 − alpha)^(1/n_tests)` keeps the family-wise false-rejection probability at
/// `alpha`. Computed as `−expm1(ln1p(−alpha)/n)` (accurate for tiny levels). `n_tests = 0` is
/// treated as 1.
#[must_use]
pub fn sidak_alpha(alpha: f64, n_tests: usize) -> f64 {
    let n = n_tests.max(1) as f64;
    -libm::expm1(libm::log1p(-alpha) / n)
}

// ---------------------------------------------------------------------------------------------
// Pearson chi-square with pooling
// ---------------------------------------------------------------------------------------------

/// Result of a Pearson chi-square goodness-of-fit test ([`SphereChi2::run`], [`chi2_1d`],
/// [`chi2_counts`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Chi2Outcome {
    /// Pearson statistic `Σ (O − E)² / E` over the pooled cells (`+∞` when observations fell
    /// in cells of zero expected count, NaN when the expected counts were invalid).
    pub statistic: f64,
    /// Degrees of freedom: number of cells after pooling − 1.
    pub dof: usize,
    /// `chi2_sf(statistic, dof)`; 0 when the statistic is infinite or NaN.
    pub p_value: f64,
    /// Samples that were NaN, infinite or (for directions) not of unit length; they are left
    /// out of the histogram and make [`Chi2Outcome::passes`] fail.
    pub invalid_samples: usize,
    /// Observations that landed where the pdf is zero (for [`SphereChi2`]: a direction where
    /// the pdf is zero, or a `None` when the pdf integrates to ≥ 1; elsewhere: cells of zero
    /// expected count).
    pub zero_pdf_samples: usize,
    /// Integral of the pdf over the domain by the same quadrature that produced the expected
    /// counts (probability of the binned domain for [`chi2_1d`]; for [`chi2_counts`] the ratio
    /// of total expected to total observed count).
    pub pdf_integral: f64,
}

impl Chi2Outcome {
    /// `true` when the fit is accepted at level `alpha`: `p_value > alpha`, no invalid
    /// samples, and at least one degree of freedom (a test left with a single cell after
    /// pooling tested nothing).
    #[must_use]
    pub fn passes(&self, alpha: f64) -> bool {
        self.p_value > alpha && self.invalid_samples == 0 && self.dof >= 1
    }
}

impl fmt::Display for Chi2Outcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "chi-square = {:.4} with {} dof, p-value = {:.4e}; invalid samples: {}, \
             samples in zero-pdf cells: {}, pdf integral = {:.8}",
            self.statistic,
            self.dof,
            self.p_value,
            self.invalid_samples,
            self.zero_pdf_samples,
            self.pdf_integral
        )
    }
}

/// Pooled Pearson statistic: returns (statistic, dof, zero_pdf_samples).
///
/// Cells are sorted by expected count; the smallest are merged into one pooled cell until its
/// expected count reaches `min_expected`, then the next pooled cell starts. A final pool that
/// stays below `min_expected` joins the last emitted cell. Cells with zero expected count are
/// dropped; observations in them are counted as `zero_pdf_samples` and make the statistic
/// infinite.
fn pearson_pooled(observed: &[f64], expected: &[f64], min_expected: f64) -> (f64, usize, usize) {
    assert_eq!(observed.len(), expected.len(), "observed and expected lengths differ");
    if expected.iter().any(|e| !e.is_finite() || *e < 0.0) {
        return (f64::NAN, 0, 0);
    }
    let mut zero_pdf = 0usize;
    let mut cells: Vec<(f64, f64)> = Vec::with_capacity(expected.len());
    for (&o, &e) in observed.iter().zip(expected) {
        if e == 0.0 {
            zero_pdf += o as usize;
        } else {
            cells.push((e, o));
        }
    }
    cells.sort_by(|a, b| a.0.total_cmp(&b.0));

    let mut pooled: Vec<(f64, f64)> = Vec::with_capacity(cells.len());
    let (mut pool_e, mut pool_o) = (0.0, 0.0);
    for (e, o) in cells {
        pool_e += e;
        pool_o += o;
        if pool_e >= min_expected {
            pooled.push((pool_e, pool_o));
            pool_e = 0.0;
            pool_o = 0.0;
        }
    }
    if pool_e > 0.0 {
        match pooled.last_mut() {
            Some(last) => {
                last.0 += pool_e;
                last.1 += pool_o;
            }
            None => pooled.push((pool_e, pool_o)),
        }
    }

    let dof = pooled.len().saturating_sub(1);
    if zero_pdf > 0 {
        return (f64::INFINITY, dof, zero_pdf);
    }
    let statistic = pooled.iter().map(|&(e, o)| (o - e) * (o - e) / e).sum();
    (statistic, dof, 0)
}

fn outcome(
    observed: &[f64],
    expected: &[f64],
    min_expected: f64,
    invalid_samples: usize,
    pdf_integral: f64,
) -> Chi2Outcome {
    let (statistic, dof, zero_pdf_samples) = pearson_pooled(observed, expected, min_expected);
    let p_value = if statistic.is_finite() { chi2_sf(statistic, dof) } else { 0.0 };
    Chi2Outcome { statistic, dof, p_value, invalid_samples, zero_pdf_samples, pdf_integral }
}

/// Pearson chi-square test of already-binned counts against expected counts, with the same
/// pooling as [`SphereChi2`] (cells sorted by expected count, smallest merged until the pool
/// reaches `min_expected`).
///
/// The expected counts should sum to the total observed count; `pdf_integral` in the outcome
/// reports `Σ expected / Σ observed`.
///
/// # Panics
/// If the slices differ in length.
#[must_use]
pub fn chi2_counts(observed: &[u64], expected: &[f64], min_expected: f64) -> Chi2Outcome {
    let obs: Vec<f64> = observed.iter().map(|&o| o as f64).collect();
    let total_o: f64 = obs.iter().sum();
    let total_e: f64 = expected.iter().sum();
    outcome(&obs, expected, min_expected, 0, total_e / total_o)
}

/// Chi-square goodness of fit of a direction sampler against its pdf on the unit sphere.
///
/// The sphere is cut into `theta_bins × phi_bins` equal-area cells, uniform in
/// `z = cos θ ∈ [−1, 1]` and `φ ∈ [0, 2π)` (`φ = atan2(y, x)`). Expected counts are
/// `samples · ∫_cell pdf dω` with `dω = d(cos θ) dφ`, integrated by splitting each cell into
/// `quadrature × quadrature` sub-cells, each with a 3×3 tensor Gauss–Legendre rule (the pdf
/// is never evaluated on a cell edge or at a pole). Cells are then pooled as in Mitsuba 3:
/// sorted by expected count, the smallest merged until the pool reaches `min_expected`.
///
/// A sampler may return `None` ("no sample", e.g. a sub-probability lobe); such outcomes form
/// an extra null cell with expected count `samples · max(0, 1 − pdf_integral)`. Samples that
/// are NaN, infinite, or whose length differs from 1 by more than `UNIT_TOLERANCE` (1e-6)
/// are counted as invalid and left out. The expected counts are *not* renormalised, so a pdf
/// that integrates to more than 1 is detected.
#[derive(Clone, Debug, PartialEq)]
pub struct SphereChi2 {
    /// Cells along `cos θ` (equal widths in `cos θ`).
    pub theta_bins: usize,
    /// Cells along `φ`.
    pub phi_bins: usize,
    /// Number of calls to the sampler.
    pub samples: usize,
    /// Sub-cells per cell side for integrating the pdf (each with 3×3 Gauss–Legendre nodes).
    pub quadrature: usize,
    /// Pool cells until the pooled expected count reaches this (default 5).
    pub min_expected: f64,
}

impl Default for SphereChi2 {
    /// 16 × 32 cells, 200 000 samples, 4 × 4 quadrature sub-cells, `min_expected = 5`.
    fn default() -> Self {
        SphereChi2 { theta_bins: 16, phi_bins: 32, samples: 200_000, quadrature: 4, min_expected: 5.0 }
    }
}

/// Gauss–Legendre 3-point rule on [−1, 1] (exact for polynomials of degree ≤ 5).
const GL3_NODES: [f64; 3] = [-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4];
const GL3_WEIGHTS: [f64; 3] = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];

/// Sub-cell refinement for cells with samples but no expected count ([`SphereChi2::run`]).
const REFINED_QUADRATURE: usize = 16;

/// Largest accepted `| |v| − 1 |` for a sampled direction.
const UNIT_TOLERANCE: f64 = 1e-6;

impl SphereChi2 {
    /// Cell index of a unit direction, or `None` if the direction is invalid.
    fn cell(&self, v: DVec3) -> Option<usize> {
        if !v.is_finite() || (v.length() - 1.0).abs() > UNIT_TOLERANCE {
            return None;
        }
        let z = v.z.clamp(-1.0, 1.0);
        let mut phi = v.y.atan2(v.x);
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        let it = (((z + 1.0) * 0.5 * self.theta_bins as f64) as usize).min(self.theta_bins - 1);
        let ip = ((phi / (2.0 * PI) * self.phi_bins as f64) as usize).min(self.phi_bins - 1);
        Some(it * self.phi_bins + ip)
    }

    /// `∫ pdf dω` over every cell (row-major: `cos θ` index major, `φ` index minor).
    ///
    /// # Panics
    /// If `theta_bins`, `phi_bins` or `quadrature` is zero.
    #[must_use]
    pub fn integrate_cells(&self, pdf: impl Fn(DVec3) -> f64) -> Vec<f64> {
        assert!(self.theta_bins > 0 && self.phi_bins > 0, "SphereChi2 needs at least one cell");
        assert!(self.quadrature > 0, "SphereChi2 needs quadrature >= 1");
        (0..self.theta_bins * self.phi_bins).map(|cell| self.integrate_cell(cell, self.quadrature, &pdf)).collect()
    }

    /// `∫ pdf dω` over one cell with `q × q` sub-cells of 3×3 Gauss–Legendre nodes each (the
    /// weights include the Jacobian of the `(cos θ, φ)` map).
    fn integrate_cell(&self, cell: usize, q: usize, pdf: &impl Fn(DVec3) -> f64) -> f64 {
        let (it, ip) = (cell / self.phi_bins, cell % self.phi_bins);
        let dz = 2.0 / (self.theta_bins * q) as f64;
        let dphi = 2.0 * PI / (self.phi_bins * q) as f64;
        let nodes = |start: f64, width: f64| {
            (0..q).flat_map(move |s| {
                let mid = start + (s as f64 + 0.5) * width;
                (0..3).map(move |k| (mid + 0.5 * width * GL3_NODES[k], 0.5 * width * GL3_WEIGHTS[k]))
            })
        };
        let phis: Vec<(f64, f64, f64)> = nodes(ip as f64 * q as f64 * dphi, dphi)
            .map(|(phi, w)| {
                let (sin, cos) = phi.sin_cos();
                (cos, sin, w)
            })
            .collect();
        let mut sum = 0.0;
        for (z, wz) in nodes(-1.0 + it as f64 * q as f64 * dz, dz) {
            let r = (1.0 - z * z).max(0.0).sqrt();
            for &(c, s, wp) in &phis {
                sum += wz * wp * pdf(DVec3::new(r * c, r * s, z));
            }
        }
        sum
    }

    /// Draw `self.samples` directions with `sample`, bin them, and test them against `pdf`
    /// (solid-angle density over the whole sphere; zero where the sampler never goes).
    ///
    /// # Panics
    /// If `theta_bins`, `phi_bins` or `quadrature` is zero.
    pub fn run(
        &self,
        pdf: impl Fn(DVec3) -> f64,
        mut sample: impl FnMut(&mut Pcg32) -> Option<DVec3>,
        rng: &mut Pcg32,
    ) -> Chi2Outcome {
        let integrals = self.integrate_cells(&pdf);
        let pdf_integral: f64 = integrals.iter().sum();
        let n = self.samples as f64;
        let n_cells = integrals.len();
        let (null_cell, zero_pdf_cell) = (n_cells, n_cells + 1);
        let mut expected: Vec<f64> = integrals.iter().map(|&p| p * n).collect();
        expected.push(n * (1.0 - pdf_integral).max(0.0)); // the sampler returned None
        expected.push(0.0); // samples where the pdf itself is zero
        let mut observed = vec![0.0f64; n_cells + 2];
        let mut under_resolved = vec![false; n_cells];
        let mut invalid = 0usize;
        for _ in 0..self.samples {
            match sample(rng) {
                None => observed[null_cell] += 1.0,
                Some(v) => match self.cell(v) {
                    // A cell cut by a discontinuity of the pdf (a visibility great circle,
                    // the horizon jump of GGX/GTR) may have all its nodes on the zero side
                    // while a sliver of it is not: a sample there is judged by the pdf at the
                    // sample, and only samples where the pdf is zero count as such.
                    Some(i) if expected[i] == 0.0 && pdf(v) > 0.0 => {
                        under_resolved[i] = true;
                        observed[i] += 1.0;
                    }
                    Some(i) if expected[i] == 0.0 => observed[zero_pdf_cell] += 1.0,
                    Some(i) => observed[i] += 1.0,
                    None => invalid += 1,
                },
            }
        }
        // Integrate the under-resolved cells again, REFINED_QUADRATURE× finer in each
        // direction; a sliver still below that resolution keeps the smallest positive count,
        // so pooling merges it with the other nearly empty cells.
        for cell in (0..n_cells).filter(|&c| under_resolved[c]) {
            let refined = n * self.integrate_cell(cell, REFINED_QUADRATURE * self.quadrature, &pdf);
            expected[cell] = refined.max(f64::MIN_POSITIVE);
        }
        let pdf_integral = expected[..n_cells].iter().sum::<f64>() / n;
        outcome(&observed, &expected, self.min_expected, invalid, pdf_integral)
    }
}

/// Chi-square goodness of fit of scalar samples against a cdf `F(x) = P(X ≤ x)` on the cells
/// `(edges[i], edges[i+1]]`, with expected counts `n·(F(edges[i+1]) − F(edges[i]))`.
///
/// Samples `≤ edges[0]` or `> edges[last]` (including `±∞`) fall in an extra outside cell with
/// expected count `n·(F(edges[0]) + 1 − F(edges[last]))`, so atoms of the distribution are
/// handled consistently with a right-continuous cdf. NaN samples are invalid. Cells are pooled
/// to an expected count of at least 5. `pdf_integral` reports `F(edges[last]) − F(edges[0])`.
///
/// # Panics
/// If `edges` has fewer than 2 entries or is not strictly increasing.
#[must_use]
pub fn chi2_1d(cdf: impl Fn(f64) -> f64, samples: &[f64], edges: &[f64]) -> Chi2Outcome {
    assert!(edges.len() >= 2, "chi2_1d needs at least two edges");
    assert!(edges.windows(2).all(|w| w[0] < w[1]), "chi2_1d edges must be strictly increasing");
    let n_cells = edges.len() - 1;
    let cdf_values: Vec<f64> = edges.iter().map(|&e| cdf(e)).collect();
    let mut valid = 0usize;
    let mut invalid = 0usize;
    let mut observed = vec![0.0f64; n_cells + 1];
    for &x in samples {
        if x.is_nan() {
            invalid += 1;
            continue;
        }
        valid += 1;
        if x <= edges[0] || x > edges[n_cells] {
            observed[n_cells] += 1.0;
        } else {
            // First edge >= x, minus one: cell (edges[i], edges[i+1]] containing x.
            let i = edges.partition_point(|&e| e < x) - 1;
            observed[i] += 1.0;
        }
    }
    let n = (valid + invalid) as f64;
    let mut expected: Vec<f64> = cdf_values.windows(2).map(|w| n * (w[1] - w[0])).collect();
    let inside = cdf_values[n_cells] - cdf_values[0];
    expected.push(n * (1.0 - inside).max(0.0));
    outcome(&observed, &expected, 5.0, invalid, inside)
}

// ---------------------------------------------------------------------------------------------
// Kolmogorov–Smirnov
// ---------------------------------------------------------------------------------------------

/// Result of [`ks_test`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KsOutcome {
    /// `D_n = sup_x |F_n(x) − F(x)|`.
    pub statistic: f64,
    /// `Q_KS((√n + 0.12 + 0.11/√n)·D_n)` (Stephens' small-sample correction).
    pub p_value: f64,
}

impl KsOutcome {
    /// `p_value > alpha` (false for NaN).
    #[must_use]
    pub fn passes(&self, alpha: f64) -> bool {
        self.p_value > alpha
    }
}

impl fmt::Display for KsOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "KS statistic D = {:.6}, p-value = {:.4e}", self.statistic, self.p_value)
    }
}

/// Largest float below `x` (`x` itself for NaN and −∞).
fn float_below(x: f64) -> f64 {
    if x.is_nan() || x == f64::NEG_INFINITY {
        x
    } else if x == 0.0 {
        -f64::from_bits(1)
    } else if x > 0.0 {
        f64::from_bits(x.to_bits() - 1)
    } else {
        f64::from_bits(x.to_bits() + 1)
    }
}

/// One-sample Kolmogorov–Smirnov test of `samples` against the cdf `F(x) = P(X ≤ x)`
/// (right-continuous). Sorts `samples` in place.
///
/// The p-value is the asymptotic Kolmogorov law with Stephens' correction,
/// `Q_KS((√n + 0.12 + 0.11/√n)·D)`; it is exact in the limit and conservative-to-accurate for
/// `n ≳ 30` with a continuous `F` (with atoms the test is conservative).
///
/// **Atoms** are supported: for each distinct sample value `c` the left limit `F(c⁻)` is taken
/// as `F` at the float just below `c`. In particular a "passed through" probability mass can
/// be tested by mapping those samples to `+∞` and having `cdf(+∞) = 1`, while `cdf(x)` for
/// finite `x` tends to `1 − mass` (the left limit at `+∞` is read at `f64::MAX`).
///
/// With no samples, or if a sample or a cdf value is NaN, the outcome is NaN statistic with
/// p-value 0 (it fails).
#[must_use]
pub fn ks_test(samples: &mut [f64], cdf: impl Fn(f64) -> f64) -> KsOutcome {
    let failed = KsOutcome { statistic: f64::NAN, p_value: 0.0 };
    if samples.is_empty() || samples.iter().any(|x| x.is_nan()) {
        return failed;
    }
    samples.sort_by(f64::total_cmp);
    let n = samples.len();
    let nf = n as f64;
    let mut d = 0.0f64;
    let mut i = 0;
    while i < n {
        let c = samples[i];
        let mut j = i + 1;
        while j < n && samples[j] == c {
            j += 1;
        }
        // Tied values occupy ranks i..j (0-based): F_n(c⁻) = i/n, F_n(c) = j/n.
        let f_at = cdf(c);
        let f_below = if c == f64::NEG_INFINITY { 0.0 } else { cdf(float_below(c)) };
        if f_at.is_nan() || f_below.is_nan() {
            return failed;
        }
        d = d.max(j as f64 / nf - f_at).max(f_below - i as f64 / nf);
        i = j;
    }
    let sqrt_n = nf.sqrt();
    let p_value = kolmogorov_sf((sqrt_n + 0.12 + 0.11 / sqrt_n) * d);
    KsOutcome { statistic: d, p_value }
}

// ---------------------------------------------------------------------------------------------
// Mean and standard error
// ---------------------------------------------------------------------------------------------

/// Mean and standard error of the mean, `s/√n` with the unbiased sample variance `s²`, by
/// Welford's numerically stable running update. For furnace tests:
/// `assert!((mean − expected).abs() < 4.0 * se)`.
///
/// No values gives `(NaN, NaN)`; one value gives `(value, NaN)` (an unknown error must not
/// make a tolerance check pass).
#[must_use]
pub fn mean_and_standard_error(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let mut n = 0u64;
    let mut mean = 0.0;
    let mut m2 = 0.0;
    for x in values {
        n += 1;
        let delta = x - mean;
        mean += delta / n as f64;
        m2 += delta * (x - mean);
    }
    match n {
        0 => (f64::NAN, f64::NAN),
        1 => (mean, f64::NAN),
        _ => {
            let nf = n as f64;
            (mean, (m2 / (nf - 1.0) / nf).sqrt())
        }
    }
}
