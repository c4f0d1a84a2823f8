//! The anisotropic Beckmann distribution: the height-field macrofacet of seeds/000 Sec. 4.1, a
//! GPSS with a squared-exponential kernel and `l_z = ∞` (so `alpha_z = 0`).

use super::gaussian_gradient::GaussianGradient;
use super::gpss::Gpss;
use super::{MicrofacetDistribution, Side};
use crate::error::Result;
use crate::limits::check_roughness;
use glam::DVec3;
use std::f64::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Beckmann {
    pub alpha_u: f64,
    pub alpha_v: f64,
}

impl Beckmann {
    /// `alpha_u` along the local tangent `x`, `alpha_v` along `y` (the `alpha_x`, `alpha_y` of
    /// [`super::Gpss`], which follows the paper's kernel axes); both within
    /// [`crate::limits::ROUGHNESS_RANGE`].
    pub fn new(alpha_u: f64, alpha_v: f64) -> Result<Beckmann> {
        Ok(Beckmann { alpha_u: check_roughness("parameter \"alpha_u\"", alpha_u)?, alpha_v: check_roughness("parameter \"alpha_v\"", alpha_v)? })
    }

    pub(super) fn gradient(&self) -> GaussianGradient {
        GaussianGradient::diagonal(DVec3::new(self.alpha_u, self.alpha_v, 0.0))
    }

    /// [`Gpss::projected_area_bound`] with `alpha_z = 0`: the Beckmann projected area is the
    /// gpss one of a height field (the same code, [`GaussianGradient`]).
    pub fn projected_area_bound(&self, z: [f64; 2], side: Side) -> Option<f64> {
        Gpss { alpha_x: self.alpha_u, alpha_y: self.alpha_v, alpha_z: 0.0 }.projected_area_bound(z, side)
    }
}

impl MicrofacetDistribution for Beckmann {
    /// `D(m) = exp(-(m_x²/α_u² + m_y²/α_v²)/m_z²) / (π α_u α_v m_z⁴)` for `m_z > 0`.
    ///
    /// Toward the horizon `exp(−e)` underflows and `m_z⁴` underflows with it (`m_z ≲ 1e-81`), and
    /// their quotient would be `0/0` = NaN: there it is formed as one exponential
    /// `exp(−e − 4 ln m_z)`, whose exponent is `−∞` or finite, never NaN, and `D → 0` is the
    /// limit. Where both are normal numbers (`e < 700`, `m_z > 1e-60`) the quotient itself,
    /// without the logarithm.
    fn d(&self, m: DVec3) -> f64 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let tilt = (m.x / self.alpha_u).powi(2) + (m.y / self.alpha_v).powi(2);
        let z2 = m.z * m.z;
        // `tilt = 0` only at the pole (`m_z = 1`), where `e = 0` (not `0/0` when `m_z²` underflows).
        let e = if tilt == 0.0 { 0.0 } else { tilt / z2 };
        let scale = PI * self.alpha_u * self.alpha_v;
        if e < 700.0 && m.z > 1e-60 {
            return (-e).exp() / (scale * z2 * z2);
        }
        (-e - 4.0 * m.z.ln()).exp() / scale
    }

    /// seeds/000 Eq. 32 with `alpha_z = 0`: the Beckmann projected area `(1 + Λ(w)) cos θ_w`.
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
