//! The visible-normal sampler of seeds/000 Eq. 40: with probability `R` a Beckmann visible normal
//! (the height-field limit of the generalized NDF), otherwise a uniform direction on the
//! hemisphere around `wi`. Kept for comparison with the paper; [`super::Gpss::sample_visible`] is
//! exact and is the default.

use super::{Gpss, MicrofacetDistribution};
use crate::error::{Error, ErrorKind, Result};
use glam::DVec3;
use std::f64::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BeckmannUniformMixture {
    pub ndf: Gpss,
    /// `R` of seeds/000 Eq. 40, in `(0, 1)`: `R = 1` would miss the downward-facing visible normals and
    /// `R = 0` ignores the peak.
    pub ratio: f64,
}

impl BeckmannUniformMixture {
    pub fn new(ndf: Gpss, ratio: f64) -> Result<Self> {
        if !(ratio > 0.0 && ratio < 1.0) {
            return Err(Error::new(
                ErrorKind::InvalidValue,
                format!("parameter \"mixture_ratio\" must lie in (0, 1), got {ratio}"),
            ));
        }
        Ok(BeckmannUniformMixture { ndf, ratio })
    }

    /// Samples `m` with `u[0]` choosing the strategy (and then reused, rescaled, for it).
    /// `None` when no flake is visible from `wi` ([`MicrofacetDistribution::visible_area`]): the
    /// uniform strategy would otherwise return normals of zero `D_wi` and a `0/0` weight.
    pub fn sample(&self, wi: DVec3, u: [f64; 3]) -> Option<DVec3> {
        self.ndf.visible_area(wi)?;
        if u[0] < self.ratio {
            let u0 = u[0] / self.ratio;
            self.ndf.beckmann().sample_visible(wi, [u0, u[1], u[2]])
        } else {
            uniform_hemisphere_around(wi, (u[0] - self.ratio) / (1.0 - self.ratio), u[1])
        }
    }

    /// `P(m) = R P_Beckmann(m) + (1 − R) / (2π)` on the hemisphere around `wi` (seeds/000 Eq. 40).
    /// Zero when no flake is visible from `wi`, as [`Self::sample`] then returns nothing.
    pub fn pdf(&self, wi: DVec3, m: DVec3) -> f64 {
        if wi.dot(m) <= 0.0 || self.ndf.visible_area(wi).is_none() {
            return 0.0;
        }
        self.ratio * self.ndf.beckmann().pdf_visible(wi, m) + (1.0 - self.ratio) / (2.0 * PI)
    }
}

/// A uniform direction on the hemisphere around `axis` (`cos θ` uniform in `(0, 1]`).
pub(super) fn uniform_hemisphere_around(axis: DVec3, u0: f64, u1: f64) -> Option<DVec3> {
    let cos = 1.0 - u0;
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let (s, t) = axis.any_orthonormal_pair();
    let phi = 2.0 * PI * u1;
    ((s * phi.cos() + t * phi.sin()) * sin + axis * cos).try_normalize()
}
