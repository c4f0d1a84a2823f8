//! A GPIS configured for rendering: kernel, memory model, march settings and the reflectance of
//! the realized surface. Built from the same named parameters as the macrofacet medium
//! ([`crate::params::gpis_from_params`]) so that a scene can switch between the statistical
//! medium and the realization-based ground truth by changing only the type.

use super::{GpisTracer, MarchSettings, MeanSdf, Memory, SeKernel, StartState, Trace};
use crate::fresnel::fresnel_conductor_rgb;
use crate::phase::{reflect, MicroBsdf};
use crate::Rgb;
use glam::DVec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpisSurface {
    pub kernel: SeKernel,
    pub memory: Memory,
    pub settings: MarchSettings,
    /// Mirror or conductor: the realized surface reflects specularly about its sampled normal.
    pub micro_bsdf: MicroBsdf,
}

impl GpisSurface {
    /// Signed-distance band `envelope σ` outside which the tracer does not sample: a host may
    /// start its rays at the boundary `f = envelope σ` of the mean surface.
    pub fn envelope(&self) -> f64 {
        self.settings.envelope * self.kernel.sigma
    }

    /// The first entering crossing of a fresh realization along the ray (seeds/004 Alg. 1).
    pub fn trace<M: MeanSdf>(
        &self,
        mean: &M,
        origin: DVec3,
        d: DVec3,
        t_max: f64,
        start: &StartState,
        uniform: &mut impl FnMut() -> f64,
    ) -> Trace {
        let tracer = GpisTracer { mean, kernel: self.kernel, settings: self.settings };
        tracer.trace(origin, d, t_max, start, uniform)
    }

    /// Specular reflection at a crossing with outward normal `n`; `wi` points away from the
    /// surface (toward where the light comes from). Returns the reflected direction and the
    /// Fresnel weight, or `None` when `wi` lies behind the normal.
    pub fn reflect(&self, wi: DVec3, n: DVec3) -> Option<(DVec3, Rgb)> {
        let cos = wi.dot(n);
        if !(cos > 0.0) {
            return None;
        }
        let weight = match self.micro_bsdf {
            MicroBsdf::Mirror { specular_reflectance } => specular_reflectance,
            MicroBsdf::Conductor { eta, k, specular_reflectance } => {
                let f = fresnel_conductor_rgb(cos, eta, k);
                [0, 1, 2].map(|c| f[c] * specular_reflectance[c])
            }
            MicroBsdf::Diffuse { .. } => return None,
        };
        Some((reflect(wi, n).normalize(), weight))
    }
}
