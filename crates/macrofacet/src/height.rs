//! The height (signed-distance) statistics of the shell, seeds/000 Eq. 5 and 13.
//!
//! SDF sign (design notes): `f > 0` above/outside the mean surface, `f < 0` inside.
//!
//! **What happens below the shell.** The paper draws the shell as `[-3σ, +3σ]`, but the flake
//! density `ρ(f) = φ(f;0,σ²)/Φ(f;0,σ²)` grows like `|f|/σ²` below the surface, and cutting it at
//! `-3σ` lets about 0.3 % of normally incident light through (design notes). Here the density is
//! **not** cut below: the interior continues with the same `ρ(f)`, so the optical depth to
//! `f -> -∞` is infinite (`ln Φ -> -∞`) and an opaque object stays opaque. Only the top is cut:
//! above `+kσ` (`shell_extent = k`, default 3) the density is zero, which removes the flakes a
//! ray would meet there with probability `1 − Φ(k)` (1.3e-3 for k = 3) — that bounds the region
//! a host must march through.

use crate::error::Result;
use crate::limits::{check_shell_extent, check_sigma};
use crate::special::{ln_normal_cdf, normal_pdf_over_cdf, probit_of_ln};

/// Default `k` of the `+kσ` top face (seeds/000 Sec. 4 uses 3σ).
pub const DEFAULT_SHELL_EXTENT: f64 = 3.0;
/// `ln Φ(3)`, [`ln_normal_cdf`]`(DEFAULT_SHELL_EXTENT)` to the bit (a unit test checks it).
const LN_CDF_DEFAULT_TOP: f64 = -1.3508099647481933e-3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeightProfile {
    /// Standard deviation of the heights (scene units), seeds/000 Eq. 5.
    pub sigma: f64,
    /// `k`: the shell's top face is at `f = k σ`.
    pub shell_extent: f64,
}

impl HeightProfile {
    /// `sigma` within [`crate::limits::SIGMA_RANGE`], `shell_extent` within
    /// [`crate::limits::SHELL_EXTENT_RANGE`].
    pub fn new(sigma: f64, shell_extent: f64) -> Result<HeightProfile> {
        Ok(HeightProfile { sigma: check_sigma("parameter \"sigma\"", sigma)?, shell_extent: check_shell_extent(shell_extent)? })
    }

    /// Signed distance of the shell's top face, `kσ`.
    pub fn top(&self) -> f64 {
        self.shell_extent * self.sigma
    }

    /// `ρ(f) = φ(f;0,σ²) / Φ(f;0,σ²)` (seeds/000 Eq. 13), zero above the top face.
    pub fn density(&self, f: f64) -> f64 {
        if f > self.top() {
            0.0
        } else {
            normal_pdf_over_cdf(f / self.sigma) / self.sigma
        }
    }

    /// `ln Φ(min(f, kσ)/σ)`: an antiderivative of [`Self::density`] in `f`. At and above the
    /// top face it is the shell's constant `ln Φ(k)` (also for a NaN `f`, as `f.min(kσ)` gave).
    pub fn ln_cdf(&self, f: f64) -> f64 {
        if !(f < self.top()) {
            return self.ln_cdf_top();
        }
        ln_normal_cdf(f / self.sigma)
    }

    /// `ln Φ(k)`, where every ray enters the shell: `k` itself rather than `kσ/σ` (within an
    /// ulp of it), so that the default `k = 3` is a constant instead of ~250 instructions at
    /// every segment that starts on the top face.
    fn ln_cdf_top(&self) -> f64 {
        if self.shell_extent == DEFAULT_SHELL_EXTENT {
            LN_CDF_DEFAULT_TOP
        } else {
            ln_normal_cdf(self.shell_extent)
        }
    }

    /// `ln Φ(fb/σ) − ln Φ(fa/σ)` for `fa, fb <= kσ`. Beyond `|f| ≈ 1.34e154 σ` both logarithms
    /// are `−∞` and their difference NaN; there `ln Φ(x) = −x²/2 − ln(−x) − ln √(2π)` to f64
    /// precision (the next term is `−1/x²`), so the difference is
    /// `−(xb − xa)(xb + xa)/2 − ln(xb/xa)`, which stays finite or overflows to `±∞` as it should
    /// (found by fuzzing: a long segment far inside had τ = 0).
    fn ln_cdf_difference(&self, fa: f64, fb: f64) -> f64 {
        self.ln_cdf_difference_of(fa, fb, self.ln_cdf(fa), self.ln_cdf(fb))
    }

    /// [`Self::ln_cdf_difference`] with `ln_a = ln_cdf(fa)` and `ln_b = ln_cdf(fb)` known.
    fn ln_cdf_difference_of(&self, fa: f64, fb: f64, ln_a: f64, ln_b: f64) -> f64 {
        if ln_a.is_finite() || ln_b.is_finite() {
            return ln_b - ln_a;
        }
        // (xb − xa) and (xb + xa) from the f's: x itself overflows beyond |f| = 1.8e308 σ
        // (found by fuzzing: σ = 1e-50, f = −5e258 gave NaN, so T = 1 deep inside).
        let (dx, sx) = ((fb - fa) / self.sigma, (fb + fa) / self.sigma);
        if dx == 0.0 {
            return 0.0;
        }
        -0.5 * dx * sx - (fb / fa).ln()
    }
}

/// Below this `|Δf|/σ` the integral of the density along a segment uses 3-point Gauss–Legendre
/// instead of differencing logarithms (which would lose `ε |ln Φ| / (|Δf|/σ)`); the rule's error
/// there is `O((Δf/σ)^6)`, far below 1e-15.
const SMALL_DELTA: f64 = 1e-3;

impl HeightProfile {
    /// `∫_0^t ρ(f0 + k u) du` along a segment on which the signed distance is linear with slope
    /// `k` (scene units per unit length; `k = d·n` for a planar shell), `t` may be `+∞`. Since
    /// `d/df ln Φ(f/σ) = ρ(f)`, the integral is `[ln Φ(f1/σ) − ln Φ(f0/σ)] / k` over the part of the
    /// segment below the top face (seeds/000 Eq. 13; the closed form of the design notes).
    pub fn density_integral(&self, f0: f64, slope: f64, t: f64) -> f64 {
        if !(t > 0.0) {
            return 0.0;
        }
        let top = self.top();
        if slope == 0.0 {
            // Parallel to the mean surface: constant density (zero above the top face).
            let rho = self.density(f0);
            return if rho == 0.0 { 0.0 } else { t * rho };
        }
        if slope > 0.0 && f0 >= top {
            // Rising from the top face or above it: above the shell for every s > 0, even where
            // f0 + s·slope rounds back to f0 (found by fuzzing: T(1) = 0.99962, T(1e10) = 1).
            return 0.0;
        }
        // The end value without forming ∞·0 for an infinite segment.
        let f1 = if t == f64::INFINITY { slope.signum() * f64::INFINITY } else { f0 + slope * t };
        let (above0, above1) = (f0 > top, f1 > top);
        if above0 && above1 {
            return 0.0; // the whole segment lies above the shell
        }
        if f1 == f64::NEG_INFINITY {
            return f64::INFINITY; // ρ grows like |f|/σ² below: unbounded optical depth
        }
        let (fa, fb) = (f0.min(top), f1.min(top));
        if (fb - fa).abs() <= SMALL_DELTA * self.sigma {
            // Nearly parallel: the length below the top face times the mean density there. The
            // length comes from where the line meets the face, not from `f1`: `f0 + t·slope`
            // may round onto the face while the segment leaves it (found by fuzzing: a shorter
            // segment transmitted less than a longer one).
            let inside = if slope > 0.0 {
                t.min((top - f0) / slope)
            } else if above0 {
                (t - (f0 - top) / -slope).max(0.0)
            } else {
                t
            };
            let (mid, half) = (0.5 * (fa + fb), 0.5 * (fb - fa));
            let node = half * (0.6f64).sqrt();
            let mean = (5.0 * self.density(mid - node) + 8.0 * self.density(mid) + 5.0 * self.density(mid + node)) / 18.0;
            // An infinite length where the density underflows to 0 (near a top face at 40σ,
            // found by fuzzing) has no flakes: 0, not ∞·0.
            return if mean == 0.0 { 0.0 } else { inside * mean };
        }
        // Both factors change sign together; rounding may leave a tiny negative value.
        (self.ln_cdf_difference(fa, fb) / slope).max(0.0)
    }

    /// The smallest `t ∈ [0, t_max]` with `density_integral(f0, slope, t) = target`, or `None`
    /// when the integral over `[0, t_max]` stays below `target` (`target >= 0`). Inverts `Φ`
    /// analytically (`ln Φ(f/σ) = ln Φ(f_s/σ) + k · target`), then polishes with Newton steps
    /// safeguarded by a bracket, which keeps nearly parallel segments accurate.
    pub fn invert_density_integral(&self, f0: f64, slope: f64, t_max: f64, target: f64) -> Option<f64> {
        if !(t_max > 0.0) {
            return None;
        }
        if slope != 0.0 {
            // The closed form: with both ends' ln Φ computed once, the total decides passing and
            // the inverse is exact unless the segment is nearly parallel (then polished below).
            let top = self.top();
            let f_start = f0.min(top);
            let f_end = if t_max == f64::INFINITY { slope.signum() * f64::INFINITY } else { f0 + slope * t_max };
            if (f0 > top && f_end > top) || (slope > 0.0 && f0 >= top) {
                return None; // above the shell for every s > 0 (as in density_integral)
            }
            if (f_end.min(top) - f_start).abs() > SMALL_DELTA * self.sigma {
                let ln_start = self.ln_cdf(f_start);
                let ln_target = ln_start + slope * target;
                // The distance at which f reaches the level where ln Φ is ln_target; none near
                // the start (polished below) or where it is not finite.
                let distance_to = |f: f64| {
                    if !((f - f_start).abs() > SMALL_DELTA * self.sigma) {
                        return None;
                    }
                    let t_start = if f0 > top { (f0 - top) / -slope } else { 0.0 };
                    let t = t_start + (f - f_start) / slope;
                    t.is_finite().then(|| t.clamp(t_start, t_max))
                };
                // A descending segment (one that reaches deep below the shell) mostly collides:
                // where the depth reaches `target`, when that lies before the end, is found
                // without the total (a second ln Φ); otherwise the total decides, as below.
                let descending = (slope < 0.0).then(|| self.sigma * probit_of_ln(ln_target));
                if let Some(t) = descending.filter(|&f| f >= f_end).and_then(distance_to) {
                    return Some(t);
                }
                let total = if f_end == f64::NEG_INFINITY {
                    f64::INFINITY
                } else {
                    let f_end = f_end.min(top);
                    (self.ln_cdf_difference_of(f_start, f_end, ln_start, self.ln_cdf(f_end)) / slope).max(0.0)
                };
                if !(target < total) {
                    return None;
                }
                if let Some(t) = distance_to(descending.unwrap_or_else(|| self.sigma * probit_of_ln(ln_target))) {
                    return Some(t);
                }
            }
        }
        self.polished_inverse(f0, slope, t_max, target)
    }

    /// [`Self::invert_density_integral`] for nearly parallel segments: the analytic guess
    /// polished by Newton steps on `∫ρ − target`, safeguarded by a bracket.
    fn polished_inverse(&self, f0: f64, slope: f64, t_max: f64, target: f64) -> Option<f64> {
        if !(target < self.density_integral(f0, slope, t_max)) {
            return None;
        }
        let top = self.top();
        // Where the segment enters the shell (only a descending segment can start above it).
        let t_start = if f0 > top { (f0 - top) / -slope } else { 0.0 };
        if !t_start.is_finite() {
            // Descending so slowly that the shell lies beyond f64::MAX (found by fuzzing: a
            // collision "at t = +inf"): no representable distance reaches it.
            return None;
        }
        let f_start = f0.min(top);
        let guess = if slope == 0.0 {
            target / self.density(f0)
        } else {
            let f = self.sigma * probit_of_ln(self.ln_cdf(f_start) + slope * target);
            t_start + (f - f_start) / slope
        };
        let (mut lo, mut hi) = (t_start, t_max);
        let mut t = if guess.is_finite() { guess.clamp(lo, hi) } else { lo };
        for _ in 0..100 {
            let r = self.density_integral(f0, slope, t) - target;
            if r == 0.0 {
                break;
            }
            if r < 0.0 {
                lo = t;
            } else {
                hi = t;
            }
            let rate = self.density(f0 + t * slope);
            let newton = t - r / rate;
            if rate > 0.0 && (newton - t).abs() <= 1e-14 * t.abs().max(f64::MIN_POSITIVE) {
                t = newton.clamp(lo, hi);
                break;
            }
            t = if rate > 0.0 && newton > lo && newton < hi {
                newton
            } else if hi.is_finite() {
                0.5 * (lo + hi)
            } else {
                2.0 * t.max(lo) + self.sigma // unbounded above: expand
            };
            if hi - lo <= 1e-15 * hi.abs() {
                break;
            }
        }
        // Entering the shell near f64::MAX (a direction 1e-309 off the surface), the bracket's
        // expansion overflows: no representable distance reaches the collision (found by
        // fuzzing: "scattered at t = inf").
        t.is_finite().then_some(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The constant is `ln Φ(3)` to the bit, and `ln_cdf` meets it at the top face from below
    /// (within the ulp of `kσ/σ`, whatever σ), for the default and another `k`.
    #[test]
    fn the_top_faces_ln_cdf_is_ln_phi_of_k() {
        assert_eq!(LN_CDF_DEFAULT_TOP.to_bits(), ln_normal_cdf(DEFAULT_SHELL_EXTENT).to_bits());
        for k in [DEFAULT_SHELL_EXTENT, 2.5] {
            for sigma in [1e-50, 3e-7, 0.1, 0.3, 7.0, 1e50] {
                let h = HeightProfile::new(sigma, k).unwrap();
                let (top, below) = (h.ln_cdf(h.top()), h.ln_cdf(h.top() * (1.0 - 4.0 * f64::EPSILON)));
                assert_eq!(top, ln_normal_cdf(k), "k {k}, sigma {sigma}");
                assert_eq!(h.ln_cdf(2.0 * h.top()), top);
                assert_eq!(h.ln_cdf(f64::NAN), top);
                assert!(below <= top && (top - below).abs() <= 1e-13 * top.abs(), "k {k}, sigma {sigma}: {below} vs {top}");
            }
        }
    }
}
