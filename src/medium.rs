//! The macrofacet medium: extinction (Eq. 14 / 31), analytic optical depth, transmittance and
//! free-flight sampling along a segment on which the signed distance varies linearly (a locally
//! planar shell), and the phase function of [`crate::phase`].
//!
//! Free-flight routines take the *propagation* direction `d` in the local frame (normal = `+z`),
//! the signed distance `f0` at the segment start, and a length `t` (may be `+∞`); along the
//! segment `f(t) = f0 + t d_z`. With `σ(d) = projected_area(-d) = Λ(d) cos θ_d` (Eq. 31) the
//! optical depth is `τ = σ(d)/d_z [ln Φ(f1/σ) − ln Φ(f0/σ)]`, so the transmittance is
//! `(Φ(f1/σ)/Φ(f0/σ))^{-Λ(d)}`; upward to infinity from height `h` that is Smith's
//! `G1 = Φ(h/σ)^{Λ}` (seeds/002 Eq. 20).

use crate::height::HeightProfile;
use crate::ndf::MicrofacetDistribution;
use crate::phase::MacrofacetPhase;
use crate::special::probit_of_ln;
use glam::DVec3;

/// Below this `|Δf|/σ` the optical depth integrates the density by 3-point Gauss–Legendre instead
/// of differencing logarithms (which would lose `ε |ln Φ| / (|Δf|/σ)`); the rule's error there is
/// `O((Δf/σ)^6)`, far below 1e-15.
const SMALL_DELTA: f64 = 1e-3;

/// The outcome of free-flight sampling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FreeFlight {
    /// A real collision at distance `t` along the segment.
    Scatter { t: f64 },
    /// No collision before the end of the segment.
    Pass,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MacrofacetMedium {
    pub height: HeightProfile,
    pub phase: MacrofacetPhase,
}

impl MacrofacetMedium {
    /// `σ(d) = ∫ <-d, m> D(m) dm`, the flakes' projected area against propagation along `d`.
    pub fn sigma(&self, d: DVec3) -> f64 {
        self.phase.ndf.projected_area(-d)
    }

    /// `σ_t(f, d) = ρ(f) σ(d)` (Eq. 14).
    pub fn sigma_t(&self, f: f64, d: DVec3) -> f64 {
        let s = self.sigma(d);
        if s == 0.0 {
            0.0
        } else {
            self.height.density(f) * s
        }
    }

    /// A bound of `σ_t` over a segment whose signed distance stays within `[f_min, f_max]`
    /// (either order): `ρ` decreases with `f`, so the bound is attained at the lower end.
    pub fn majorant(&self, f_a: f64, f_b: f64, d: DVec3) -> f64 {
        self.sigma_t(f_a.min(f_b), d)
    }

    /// `τ = ∫_0^t σ_t(f0 + s d_z, d) ds`, exact for the linear SDF.
    pub fn optical_depth(&self, f0: f64, d: DVec3, t: f64) -> f64 {
        if !(t > 0.0) {
            return 0.0;
        }
        let s = self.sigma(d);
        if s == 0.0 {
            return 0.0;
        }
        let h = &self.height;
        let top = h.top();
        let f1 = f0 + t * d.z;
        let (above0, above1) = (f0 > top, f1 > top);
        if above0 && above1 {
            return 0.0; // the whole segment lies above the shell
        }
        if f1 == f64::NEG_INFINITY {
            return f64::INFINITY;
        }
        let (fa, fb) = (f0.min(top), f1.min(top));
        if (fb - fa).abs() <= SMALL_DELTA * h.sigma {
            // Nearly horizontal: the length below the top face times the mean density. The
            // length is `t` itself unless the segment crosses the top face.
            let inside = if above0 || above1 { ((fb - fa) / d.z).abs().min(t) } else { t };
            if inside == f64::INFINITY {
                return f64::INFINITY;
            }
            let (mid, half) = (0.5 * (fa + fb), 0.5 * (fb - fa));
            let node = half * (0.6f64).sqrt();
            let mean = (5.0 * h.density(mid - node) + 8.0 * h.density(mid) + 5.0 * h.density(mid + node)) / 18.0;
            return s * inside * mean;
        }
        // σ(d)/d_z [ln Φ(fb/σ) − ln Φ(fa/σ)]; both factors change sign together.
        (s / d.z * (h.ln_cdf(fb) - h.ln_cdf(fa))).max(0.0)
    }

    /// `exp(-τ)` of [`Self::optical_depth`].
    pub fn transmittance(&self, f0: f64, d: DVec3, t: f64) -> f64 {
        (-self.optical_depth(f0, d, t)).exp()
    }

    /// Samples the distance to the next collision on `[0, t_max]` with density
    /// `σ_t(t) exp(-τ(t))`, by inverting `Φ`: `ln Φ(f/σ) = ln Φ(f_s/σ) + d_z τ*/σ(d)` with
    /// `τ* = -ln(1 − u)`, polished by Newton steps on `τ(t) = τ*` (which keeps nearly horizontal
    /// rays accurate). Returns [`FreeFlight::Pass`] with probability `exp(-τ(t_max))`.
    pub fn sample_free_flight(&self, f0: f64, d: DVec3, t_max: f64, u: f64) -> FreeFlight {
        let s = self.sigma(d);
        if s == 0.0 || !(t_max > 0.0) {
            return FreeFlight::Pass;
        }
        let target = -(-u).ln_1p();
        if target >= self.optical_depth(f0, d, t_max) {
            return FreeFlight::Pass;
        }
        let h = &self.height;
        let top = h.top();
        // Where the segment enters the shell (only a downward ray can start above it).
        let t_start = if f0 > top { (f0 - top) / -d.z } else { 0.0 };
        let f_start = f0.min(top);
        let guess = if d.z == 0.0 {
            target / (s * h.density(f0))
        } else {
            let f = h.sigma * probit_of_ln(h.ln_cdf(f_start) + d.z * target / s);
            t_start + (f - f_start) / d.z
        };
        // Newton on τ(t) − τ* (τ increases, with derivative σ_t(f(t))), safeguarded by a bracket
        // so that a poor analytic guess (nearly horizontal rays) still converges.
        let (mut lo, mut hi) = (t_start, t_max);
        let mut t = if guess.is_finite() { guess.clamp(lo, hi) } else { lo };
        for _ in 0..100 {
            let r = self.optical_depth(f0, d, t) - target;
            if r == 0.0 {
                break;
            }
            if r < 0.0 {
                lo = t;
            } else {
                hi = t;
            }
            let slope = self.sigma_t(f0 + t * d.z, d);
            let newton = t - r / slope;
            if slope > 0.0 && (newton - t).abs() <= 1e-14 * t.abs().max(f64::MIN_POSITIVE) {
                t = newton.clamp(lo, hi);
                break;
            }
            t = if slope > 0.0 && newton > lo && newton < hi {
                newton
            } else if hi.is_finite() {
                0.5 * (lo + hi)
            } else {
                2.0 * t.max(lo) + self.height.sigma // unbounded above: expand
            };
            if hi - lo <= 1e-15 * hi.abs() {
                break;
            }
        }
        FreeFlight::Scatter { t }
    }
}
