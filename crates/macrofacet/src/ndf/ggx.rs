//! The anisotropic GGX / Trowbridge–Reitz distribution, the "artist choice" of seeds/000 Sec. 4.1.

use super::{MicrofacetDistribution, Side};
use crate::error::Result;
use crate::limits::check_roughness;
use glam::DVec3;
use std::f64::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    pub alpha_u: f64,
    pub alpha_v: f64,
}

impl Ggx {
    /// Both roughnesses within [`crate::limits::ROUGHNESS_RANGE`].
    pub fn new(alpha_u: f64, alpha_v: f64) -> Result<Ggx> {
        Ok(Ggx { alpha_u: check_roughness("parameter \"alpha_u\"", alpha_u)?, alpha_v: check_roughness("parameter \"alpha_v\"", alpha_v)? })
    }

    /// The "stretch" that maps the GGX ellipsoid to the unit sphere (Heitz 2018).
    fn stretch(&self) -> DVec3 {
        DVec3::new(self.alpha_u, self.alpha_v, 1.0)
    }

    /// The upper or lower bound of the projected area over every direction `w` with `w_z` in
    /// `[z[0], z[1]]`, for `alpha_u = alpha_v <= 1` (`None` otherwise): the area
    /// `(w_z + sqrt(α² + (1 − α²) w_z²))/2` then grows with `w_z`, so the range's ends bound it.
    pub fn projected_area_bound(&self, z: [f64; 2], side: Side) -> Option<f64> {
        if self.alpha_u != self.alpha_v || self.alpha_u > 1.0 {
            return None;
        }
        let at = |z: f64| self.projected_area(DVec3::new(((1.0 - z) * (1.0 + z)).max(0.0).sqrt(), 0.0, z));
        Some(match side {
            Side::Upper => at(z[1]),
            Side::Lower => at(z[0]),
        })
    }
}

impl MicrofacetDistribution for Ggx {
    /// `D(m) = 1 / (π α_u α_v (m_x²/α_u² + m_y²/α_v² + m_z²)²)` for `m_z > 0`.
    fn d(&self, m: DVec3) -> f64 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let q = (m.x / self.alpha_u).powi(2) + (m.y / self.alpha_v).powi(2) + m.z * m.z;
        1.0 / (PI * self.alpha_u * self.alpha_v * q * q)
    }

    /// `(1 + Λ(w)) cos θ = (w_z + sqrt(α_u² w_x² + α_v² w_y² + w_z²)) / 2`, valid on the whole
    /// sphere; for `w_z < 0` the rationalised form avoids cancellation.
    fn projected_area(&self, w: DVec3) -> f64 {
        let t2 = (self.alpha_u * w.x).powi(2) + (self.alpha_v * w.y).powi(2);
        let root = (t2 + w.z * w.z).sqrt();
        if w.z >= 0.0 {
            0.5 * (w.z + root)
        } else {
            0.5 * t2 / (root - w.z)
        }
    }

    /// Exact, on the whole sphere of `wi`: in the stretched configuration the visible normals of
    /// the upper half-sphere are `normalize(wi + c)` with `c` uniform on the spherical cap
    /// `c_z > -wi_z` (Dupuy & Benyoub 2023, a reformulation of Heitz 2018). Uses `u[0], u[1]`.
    fn sample_visible(&self, wi: DVec3, u: [f64; 3]) -> Option<DVec3> {
        let wi_std = (wi * self.stretch()).try_normalize()?;
        let phi = 2.0 * PI * u[1];
        let z = (1.0 - u[0]) * (1.0 + wi_std.z) - wi_std.z;
        let sin = (1.0 - z * z).max(0.0).sqrt();
        let cap = DVec3::new(sin * phi.cos(), sin * phi.sin(), z);
        let m_std = (cap + wi_std).try_normalize()?;
        let m = (m_std * self.stretch()).try_normalize()?;
        (m.z > 0.0 && wi.dot(m) > 0.0).then_some(m)
    }

    /// `m ∝ D(m)(m·n)`: in the stretched configuration the slope radius has
    /// `r² = u/(1 − u)` (Walter et al. 2007), then the stretch.
    fn sample_normal(&self, u: [f64; 2]) -> Option<DVec3> {
        let r = (u[0] / (1.0 - u[0])).sqrt();
        let phi = 2.0 * PI * u[1];
        DVec3::new(-self.alpha_u * r * phi.cos(), -self.alpha_v * r * phi.sin(), 1.0).try_normalize()
    }
}
