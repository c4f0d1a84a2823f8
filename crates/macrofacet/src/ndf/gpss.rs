//! The generalized macrofacet (seeds/000 Sec. 4.2): the full-sphere NDF of a GPSS whose
//! squared-exponential kernel has finite correlation length along the normal as well,
//! `alpha_i = sqrt(2) sigma / l_i` (seeds/000 Eq. 4). Normals point in every direction; `alpha_z -> 0`
//! recovers Beckmann.
//!
//! Naming: the fields follow the paper's kernel axes (`α_x, α_y, α_z` for `l_x, l_y, l_z`). The
//! in-plane pair is what [`Beckmann`] and the parameter table call `alpha_u`, `alpha_v` (along the
//! local tangent `x` and bitangent `y`): `alpha_x` = `alpha_u`, `alpha_y` = `alpha_v`.

use super::beckmann::Beckmann;
use super::gaussian_gradient::{expected_positive_part, GaussianGradient};
use super::{MicrofacetDistribution, Side};
use crate::error::Result;
use crate::limits::{check_alpha_z, check_roughness};
use crate::special::{erfc, erfcx};
use glam::DVec3;
use std::f64::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gpss {
    /// Roughness along the local tangent `x`: the parameter `alpha_u`.
    pub alpha_x: f64,
    /// Roughness along the local bitangent `y`: the parameter `alpha_v`.
    pub alpha_y: f64,
    /// `0` is allowed and means a height field: the NDF is then exactly Beckmann.
    pub alpha_z: f64,
}

impl Gpss {
    /// The in-plane roughnesses within [`crate::limits::ROUGHNESS_RANGE`], `alpha_z` 0 or within
    /// `[ALPHA_Z_MIN, ROUGHNESS_RANGE.1]`.
    pub fn new(alpha_x: f64, alpha_y: f64, alpha_z: f64) -> Result<Gpss> {
        Ok(Gpss {
            alpha_x: check_roughness("alpha_x (parameter \"alpha_u\")", alpha_x)?,
            alpha_y: check_roughness("alpha_y (parameter \"alpha_v\")", alpha_y)?,
            alpha_z: check_alpha_z("parameter \"alpha_z\"", alpha_z)?,
        })
    }

    fn gradient(&self) -> GaussianGradient {
        GaussianGradient::diagonal(DVec3::new(self.alpha_x, self.alpha_y, self.alpha_z))
    }

    /// The upper or lower bound of the projected area over every direction `w` with `w_z` in
    /// `[z[0], z[1]]`, for `alpha_x = alpha_y` (`None` otherwise): `E[max(0, w·g)]` grows with
    /// the mean `w_z` of `w·g` and with its spread `s(w)` (seeds/000 Eq. 32), and
    /// `s² = alpha² (1 − w_z²) + alpha_z² w_z²` is monotone in `w_z²`. So each bound is one
    /// evaluation at the range's extreme `w_z` and extreme spread, with no Lipschitz margin.
    /// `s²` is summed from its two non-negative terms: written `alpha_z² + (alpha² − alpha_z²)
    /// sin²`, it cancelled at grazing `w` (found by fuzzing: alpha = 3.3e-5, alpha_z = 2.7e5 gave
    /// `s = 0` at `w_z = 0`, a bound of 1.8e-15 for an area of 1.2e-5).
    pub fn projected_area_bound(&self, z: [f64; 2], side: Side) -> Option<f64> {
        if self.alpha_x != self.alpha_y {
            return None;
        }
        let z2_max = (z[0] * z[0]).max(z[1] * z[1]).min(1.0);
        let z2_min = if z[0] <= 0.0 && z[1] >= 0.0 { 0.0 } else { (z[0] * z[0]).min(z[1] * z[1]).min(1.0) };
        let (a2, az2) = (self.alpha_x * self.alpha_x, self.alpha_z * self.alpha_z);
        let s = |z2: f64| (a2 * (1.0 - z2) + az2 * z2).sqrt();
        let (s_hi, s_lo) = if a2 >= az2 { (s(z2_min), s(z2_max)) } else { (s(z2_max), s(z2_min)) };
        Some(match side {
            Side::Upper => expected_positive_part(z[1], s_hi),
            Side::Lower => expected_positive_part(z[0], s_lo),
        })
    }

    /// The height-field limit with the same in-plane roughness (used by the seeds/000 Eq. 40 mixture).
    pub fn beckmann(&self) -> Beckmann {
        Beckmann { alpha_u: self.alpha_x, alpha_v: self.alpha_y }
    }
}

impl MicrofacetDistribution for Gpss {
    /// seeds/000 Eq. 38, `D(m) = ∫_0^∞ P(t m) t³ dt` (seeds/000 Eq. 36) for `g ~ N(e_z, diag(α²)/2)`:
    /// `D = e^{-C} / (π^{3/2} α_x α_y α_z A²) [ (β² + 1)/2 + (√π/2) β (β² + 3/2) erfcx(-β) ]`
    /// with `A, B, C` of seeds/000 Eq. 38 and `β = B/√A`. That is seeds/000 Eq. 38 regrouped: `e^{-C + B²/A}` times
    /// `erfc(-β)` is `e^{-C} erfcx(-β)`. For `β >= 0` the product is formed as
    /// `e^{E} erfc(-β)` with `E = B²/A − C = −ρ/(m_z² + ρ α_z²)`, `ρ = m_x²/α_x² + m_y²/α_y²`,
    /// which neither overflows nor cancels as `α_z -> 0`.
    fn d(&self, m: DVec3) -> f64 {
        if self.alpha_z == 0.0 {
            return self.beckmann().d(m);
        }
        let rho = (m.x / self.alpha_x).powi(2) + (m.y / self.alpha_y).powi(2);
        let az2 = self.alpha_z * self.alpha_z;
        let a = rho + m.z * m.z / az2;
        let b = m.z / az2;
        let beta = b / a.sqrt();
        let prefactor = 1.0 / (PI.powf(1.5) * self.alpha_x * self.alpha_y * self.alpha_z * a * a);
        let half_sqrt_pi = 0.5 * PI.sqrt();
        let poly = beta * (beta * beta + 1.5);
        let bracket = if beta >= 0.0 {
            let e = -rho / (m.z * m.z + rho * az2);
            (-1.0 / az2).exp() * 0.5 * (beta * beta + 1.0) + half_sqrt_pi * poly * e.exp() * erfc(-beta)
        } else {
            (-1.0 / az2).exp() * (0.5 * (beta * beta + 1.0) + half_sqrt_pi * poly * erfcx(-beta))
        };
        (prefactor * bracket).max(0.0)
    }

    /// `σ(-w) = Λ(-w) cos θ` with Λ of seeds/000 Eq. 32, in the cancellation-free form of
    /// [`GaussianGradient::projected_area`].
    fn projected_area(&self, w: DVec3) -> f64 {
        self.gradient().projected_area(w)
    }

    /// Exact sampling of the generalized vNDF through the gradient-space identity (design notes).
    fn sample_visible(&self, wi: DVec3, u: [f64; 3]) -> Option<DVec3> {
        self.gradient().sample_visible(wi, u)
    }
}
