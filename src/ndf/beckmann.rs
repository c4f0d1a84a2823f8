//! The anisotropic Beckmann distribution: the height-field macrofacet of seeds/000 Sec. 4.1, a
//! GPSS with a squared-exponential kernel and `l_z = ∞` (so `alpha_z = 0`).

use super::gaussian_gradient::GaussianGradient;
use super::MicrofacetDistribution;
use crate::error::{check_positive, Result};
use glam::DVec3;
use std::f64::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Beckmann {
    pub alpha_u: f64,
    pub alpha_v: f64,
}

impl Beckmann {
    /// `alpha_u` along the local tangent `x`, `alpha_v` along `y`; both finite and `> 0`.
    pub fn new(alpha_u: f64, alpha_v: f64) -> Result<Beckmann> {
        Ok(Beckmann {
            alpha_u: check_positive("alpha_u", alpha_u, false)?,
            alpha_v: check_positive("alpha_v", alpha_v, false)?,
        })
    }

    pub(super) fn gradient(&self) -> GaussianGradient {
        GaussianGradient::diagonal(DVec3::new(self.alpha_u, self.alpha_v, 0.0))
    }
}

impl MicrofacetDistribution for Beckmann {
    /// `D(m) = exp(-(m_x²/α_u² + m_y²/α_v²)/m_z²) / (π α_u α_v m_z⁴)` for `m_z > 0`.
    fn d(&self, m: DVec3) -> f64 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let cos2 = m.z * m.z;
        let e = ((m.x / self.alpha_u).powi(2) + (m.y / self.alpha_v).powi(2)) / cos2;
        (-e).exp() / (PI * self.alpha_u * self.alpha_v * cos2 * cos2)
    }

    /// Eq. 32 with `alpha_z = 0`: the Beckmann projected area `(1 + Λ(w)) cos θ_w`.
    fn projected_area(&self, w: DVec3) -> f64 {
        self.gradient().projected_area(w)
    }

    /// Exact: the slopes are Gaussian, so the gradient-space sampler of
    /// [`GaussianGradient`] applies with `alpha_z = 0` (equivalent to Heitz & d'Eon 2014, which
    /// samples the same 1-D visible-slope density, but inverted by Newton instead of a fit).
    fn sample_visible(&self, wi: DVec3, u: [f64; 3]) -> Option<DVec3> {
        self.gradient().sample_visible(wi, u)
    }

    /// `m ∝ D(m)(m·n)`: the slopes are Gaussian with variances `α²/2` (Box–Muller).
    fn sample_normal(&self, u: [f64; 2]) -> Option<DVec3> {
        let (x, y) = super::gaussian_gradient::box_muller(u[0], u[1]);
        let s = std::f64::consts::FRAC_1_SQRT_2;
        DVec3::new(-self.alpha_u * s * x, -self.alpha_v * s * y, 1.0).try_normalize()
    }
}
