//! A GPIS configured for rendering: kernel, memory model, march settings and the reflectance of
//! the realized surface. Built from the same named parameters as the macrofacet medium
//! ([`crate::params::gpis_from_params`]) so that a scene can switch between the statistical
//! medium and the realization-based ground truth by changing only the type. A field
//! ([`macrofacet::field::MediumField`]) makes its parameters vary in space as it does the
//! macrofacet medium's ([`super::FieldKernel`]).

use super::{GpisTracer, MarchSettings, MeanSdf, Memory, SeKernel, StartState, Trace};
use macrofacet::error::Result;
use macrofacet::field::{LocalParams, MediumField};
use macrofacet::phase::{reflect, MicroBsdf};
use macrofacet::Rgb;
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
    fn tracer<'a, M: MeanSdf, F: MediumField>(&self, mean: &'a M, field: &'a F) -> GpisTracer<'a, M, F> {
        GpisTracer { mean, kernel: self.kernel, field, settings: self.settings }
    }

    /// Signed-distance band `envelope σ_max` outside which the tracer does not sample (`σ_max`:
    /// the field's, else the kernel's `σ`): a host may start its rays at the boundary
    /// `f = envelope σ_max` of the mean surface.
    pub fn envelope<F: MediumField>(&self, field: &F) -> f64 {
        self.settings.envelope * super::sigma_max(&self.kernel, field)
    }

    /// The first entering crossing of a fresh realization along the ray (seeds/004 Alg. 1), with
    /// the kernel's local parameters from `field` ([`macrofacet::field::Constant`]: stationary).
    #[allow(clippy::too_many_arguments)]
    pub fn trace<M: MeanSdf, F: MediumField>(
        &self,
        mean: &M,
        field: &F,
        origin: DVec3,
        d: DVec3,
        t_max: f64,
        start: &StartState,
        uniform: &mut impl FnMut() -> f64,
    ) -> Result<Trace> {
        self.tracer(mean, field).trace(origin, d, t_max, start, uniform)
    }

    /// Checks a Renewal+ start gradient before a march conditions on it
    /// ([`GpisTracer::check_start_gradient`]), with the kernel's local parameters from `field`.
    pub fn check_start_gradient<M: MeanSdf, F: MediumField>(&self, mean: &M, field: &F, origin: DVec3, gradient: DVec3) -> Result<()> {
        self.tracer(mean, field).check_start_gradient(origin, gradient)
    }

    /// Specular reflection at a crossing with outward normal `n` whose field parameters are
    /// `local` (its `reflectance_scale` scales the reflectance); `wi` points away from the
    /// surface (toward where the light comes from). Returns the reflected direction and the
    /// Fresnel weight, or `None` when `wi` lies behind the normal.
    pub fn reflect(&self, local: &LocalParams, wi: DVec3, n: DVec3) -> Result<Option<(DVec3, Rgb)>> {
        let micro_bsdf = match local.reflectance_scale {
            Some(scale) => self.micro_bsdf.with_reflectance_scale(scale)?,
            None => self.micro_bsdf,
        };
        let cos = wi.dot(n);
        if !(cos > 0.0) {
            return Ok(None);
        }
        Ok(micro_bsdf.specular(cos).map(|weight| (reflect(wi, n).normalize(), weight)))
    }
}
