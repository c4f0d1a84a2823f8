//! A GPIS configured for rendering: kernel, memory model, march settings and the reflectance of
//! the realized surface. Built from the same named parameters as the macrofacet medium
//! ([`crate::params::gpis_from_params`]) so that a scene can switch between the statistical
//! medium and the realization-based ground truth by changing only the type.

use super::{GpisTracer, MarchSettings, MeanSdf, Memory, SeKernel, StartState, Trace};
use crate::error::{Error, ErrorKind, Result};
use crate::fresnel::fresnel_conductor_rgb;
use crate::phase::{reflect, MicroBsdf};
use crate::Rgb;
use glam::DVec3;

/// Bound of [`GpisSurface::check_start_gradient`], in standard deviations of the prior slope.
pub const START_GRADIENT_DEVIATIONS: f64 = 40.0;

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

    /// Checks a Renewal+ start gradient before a march conditions on it: along every axis the
    /// kernel varies (`l_i < ∞`), `g_i` must lie within [`START_GRADIENT_DEVIATIONS`] standard
    /// deviations `σ/l_i = α_i/√2` (seeds/000 Eq. 4) of the mean's slope at the origin. A
    /// crossing's sampled gradient always does (beyond 40 deviations a normal law has mass
    /// below 1e-300); a gradient that does not — `DBL_MAX`, say — would make every conditioned
    /// value meaningless (issue 9 item 12). One call to the mean.
    pub fn check_start_gradient<M: MeanSdf>(&self, mean: &M, origin: DVec3, gradient: DVec3) -> Result<()> {
        let invalid = |message: String| Err(Error::new(ErrorKind::InvalidArgument, message));
        if !gradient.is_finite() {
            return invalid(format!("start.gradient must be finite, got {gradient}"));
        }
        let slope = mean.gradient(origin);
        if !slope.is_finite() {
            return invalid(format!("the sdf callback returned a NaN or infinite gradient {slope} at the origin {origin}"));
        }
        let deviation = self.kernel.sigma * self.kernel.inverse_squared_lengths().map(f64::sqrt);
        for i in 0..3 {
            let z = (gradient[i] - slope[i]).abs() / deviation[i];
            if deviation[i] > 0.0 && !(z <= START_GRADIENT_DEVIATIONS) {
                return invalid(format!(
                    "start.gradient component {i} = {} lies {z:.3e} standard deviations ({}) from the mean's slope {} at the \
                     origin: no crossing of this process has that gradient (pass the gradient of the previous mf_gpis_hit)",
                    gradient[i], deviation[i], slope[i]
                ));
            }
        }
        Ok(())
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
