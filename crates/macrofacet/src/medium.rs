//! The macrofacet medium: extinction (seeds/000 Eq. 14 / 31), analytic optical depth, transmittance and
//! free-flight sampling along a segment on which the signed distance varies linearly (a locally
//! planar shell), and the phase function of [`crate::phase`].
//!
//! Free-flight routines take the *propagation* direction `d` in the local frame (normal = `+z`),
//! the signed distance `f0` at the segment start, and a length `t` (may be `+∞`); along the
//! segment `f(t) = f0 + t d_z`. With `σ(d) = projected_area(-d) = Λ(d) cos θ_d` (seeds/000 Eq. 31) the
//! optical depth is `τ = σ(d)/d_z [ln Φ(f1/σ) − ln Φ(f0/σ)]`, so the transmittance is
//! `(Φ(f1/σ)/Φ(f0/σ))^{-Λ(d)}`; upward to infinity from height `h` that is Smith's
//! `G1 = Φ(h/σ)^{Λ}` (seeds/002 Eq. 20).

use crate::height::HeightProfile;
use crate::ndf::MicrofacetDistribution;
use crate::phase::MacrofacetPhase;
use glam::DVec3;

/// Relative margin of [`MacrofacetMedium::majorant`]: the computed `ρ` is monotone only to a
/// few ulps (its `erfcx` rounds; fuzzing found `σ_t` one ulp of `f` above the lower end larger
/// by 2e-14 relative), and a delta tracker must never accept with probability above 1.
pub const MAJORANT_ROUNDING: f64 = 1.0 + 1e-12;

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

    /// `σ_t(f, d) = ρ(f) σ(d)` (seeds/000 Eq. 14).
    pub fn sigma_t(&self, f: f64, d: DVec3) -> f64 {
        let s = self.sigma(d);
        if s == 0.0 {
            0.0
        } else {
            self.height.density(f) * s
        }
    }

    /// A bound of `σ_t` over a segment whose signed distance stays within `[f_min, f_max]`
    /// (either order): `ρ` decreases with `f`, so the bound is attained at the lower end, times
    /// [`MAJORANT_ROUNDING`].
    pub fn majorant(&self, f_a: f64, f_b: f64, d: DVec3) -> f64 {
        self.sigma_t(f_a.min(f_b), d) * MAJORANT_ROUNDING
    }

    /// `τ = ∫_0^t σ_t(f0 + s d_z, d) ds = σ(d) ∫_0^t ρ(f0 + s d_z) ds`, exact for the linear SDF
    /// ([`HeightProfile::density_integral`]).
    pub fn optical_depth(&self, f0: f64, d: DVec3, t: f64) -> f64 {
        let s = self.sigma(d);
        if s == 0.0 {
            return 0.0;
        }
        s * self.height.density_integral(f0, d.z, t)
    }

    /// `exp(-τ)` of [`Self::optical_depth`].
    pub fn transmittance(&self, f0: f64, d: DVec3, t: f64) -> f64 {
        (-self.optical_depth(f0, d, t)).exp()
    }

    /// Samples the distance to the next collision on `[0, t_max]` with density
    /// `σ_t(t) exp(-τ(t))` by inverting the optical depth at `τ* = -ln(1 − u)`
    /// ([`HeightProfile::invert_density_integral`]). Returns [`FreeFlight::Pass`] with probability
    /// `exp(-τ(t_max))`.
    pub fn sample_free_flight(&self, f0: f64, d: DVec3, t_max: f64, u: f64) -> FreeFlight {
        let s = self.sigma(d);
        if s == 0.0 {
            return FreeFlight::Pass;
        }
        let target = -(-u).ln_1p() / s;
        match self.height.invert_density_integral(f0, d.z, t_max, target) {
            Some(t) => FreeFlight::Scatter { t },
            None => FreeFlight::Pass,
        }
    }
}
