//! The visible-normal strategy of seeds/001 Appendix B for rough height fields without (or
//! besides) an exact visible-normal sampler: with probability `R` a normal from `D(m)(m·n)`
//! ([`MicrofacetDistribution::sample_normal`]), otherwise a uniform direction on the hemisphere
//! around `wi`. The density is the one-sample balance-heuristic mixture
//! `R D(m)(m·n) + (1 − R) [wi·m > 0]/(2π)`, so `eval/pdf` stays unbiased; normals drawn from
//! `D` that face away from `wi` carry no light (the phase function rejects them).

use super::mixture::uniform_hemisphere_around;
use super::{MicrofacetDistribution, Ndf};
use crate::error::{Error, ErrorKind, Result};
use glam::DVec3;
use std::f64::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalUniformMixture {
    /// `R`, in `(0, 1)`.
    pub ratio: f64,
}

impl NormalUniformMixture {
    pub fn new(ratio: f64) -> Result<Self> {
        if !(ratio > 0.0 && ratio < 1.0) {
            return Err(Error::new(
                ErrorKind::InvalidValue,
                format!("parameter \"mixture_ratio\" must lie in (0, 1), got {ratio}"),
            ));
        }
        Ok(NormalUniformMixture { ratio })
    }

    /// The paper leaves the choice to "a random number and the roughness": we favour `D`
    /// (`R = 1 − α/2`, at least 1/2) for smooth surfaces, where it is nearly the vNDF, and mix
    /// evenly for `α >= 1`.
    pub fn default_ratio(alpha: f64) -> f64 {
        (1.0 - 0.5 * alpha).clamp(0.5, 0.95)
    }

    /// Samples `m` with `u[0]` choosing the strategy (then rescaled and reused).
    pub fn sample(&self, ndf: &Ndf, wi: DVec3, u: [f64; 3]) -> Option<DVec3> {
        if u[0] < self.ratio {
            ndf.sample_normal([u[0] / self.ratio, u[1]])
        } else {
            uniform_hemisphere_around(wi, (u[0] - self.ratio) / (1.0 - self.ratio), u[1])
        }
    }

    /// The mixture density per solid angle of `m`.
    pub fn pdf(&self, ndf: &Ndf, wi: DVec3, m: DVec3) -> f64 {
        let uniform = if wi.dot(m) > 0.0 { 1.0 / (2.0 * PI) } else { 0.0 };
        self.ratio * ndf.d(m) * m.z.max(0.0) + (1.0 - self.ratio) * uniform
    }
}
