//! The macrofacet phase function, Eq. 11–12 of seeds/000, with a choice of micro-BSDF on the
//! flakes.
//!
//! Direction convention (Mitsuba 3 / pbrt): `wi` and `wo` both point *away* from the scattering
//! point. A ray travelling along `d` that scatters has `wi = -d`; the sampled `wo` is the new
//! propagation direction. All vectors are in the local frame (normal = `+z`).
//!
//! The flakes are one-sided (seeds/002 §4.1): `p(wi, wo) = F(wi·m) D_wi(m) / (4 |wi·m|)` with
//! the half vector `m = (wi + wo)/|wi + wo|` and the visible normals `D_wi` of Eq. 12, so
//! `p(wi, wo) = F D(m) / (4 σ(-wi))`. Reciprocity holds for the BRDF that emerges from a slab,
//! not event by event.

use crate::error::{Error, ErrorKind, Result};
use crate::ndf::{BeckmannUniformMixture, MicrofacetDistribution, Ndf, NormalUniformMixture};
use crate::fresnel::fresnel_conductor_rgb;
use crate::Rgb;
use glam::DVec3;
use std::f64::consts::{FRAC_1_PI, PI};

/// How many uniform random numbers [`MacrofacetPhase::sample`] consumes: three for the visible
/// normal, two for the diffuse lobe of a diffuse flake (unused otherwise).
pub const PHASE_SAMPLE_DIMENSIONS: usize = 5;

/// Points of the deterministic quasi-Monte Carlo rule that evaluates the diffuse-flake phase
/// function (no closed form exists: it is a convolution of the vNDF with a clamped cosine).
pub const DIFFUSE_EVAL_POINTS: usize = 256;

/// The reflectance model of an individual flake.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MicroBsdf {
    /// A perfect mirror scaled by `specular_reflectance` (Mitsuba's `material = "none"`).
    Mirror { specular_reflectance: Rgb },
    /// A smooth conductor with complex index `eta + i k` per channel.
    Conductor { eta: Rgb, k: Rgb, specular_reflectance: Rgb },
    /// A Lambertian flake (one-sided, facing its normal) with albedo `reflectance`.
    Diffuse { reflectance: Rgb },
}

impl MicroBsdf {
    /// Reflectance of a specular flake for an incident cosine; `None` for diffuse flakes.
    pub(crate) fn specular(&self, cos_i: f64) -> Option<Rgb> {
        match *self {
            MicroBsdf::Mirror { specular_reflectance } => Some(specular_reflectance),
            MicroBsdf::Conductor { eta, k, specular_reflectance } => {
                let f = fresnel_conductor_rgb(cos_i, eta, k);
                Some([0, 1, 2].map(|c| f[c] * specular_reflectance[c]))
            }
            MicroBsdf::Diffuse { .. } => None,
        }
    }

    /// The flake with its reflectance multiplied per channel by `scale` (a field's
    /// `reflectance_scale`, [`crate::field::LocalParams`]); the product must stay within `[0, 1]`
    /// (energy conservation of the flake).
    pub fn with_reflectance_scale(&self, scale: Rgb) -> Result<MicroBsdf> {
        let scaled = |r: Rgb| -> Result<Rgb> {
            let s = [0, 1, 2].map(|c| r[c] * scale[c]);
            if s.iter().all(|c| (0.0..=1.0).contains(c)) {
                Ok(s)
            } else {
                Err(Error::new(ErrorKind::InvalidArgument, format!("reflectance_scale {scale:?} takes the flakes' reflectance {r:?} outside [0, 1]")))
            }
        };
        Ok(match *self {
            MicroBsdf::Mirror { specular_reflectance } => MicroBsdf::Mirror { specular_reflectance: scaled(specular_reflectance)? },
            MicroBsdf::Conductor { eta, k, specular_reflectance } => MicroBsdf::Conductor { eta, k, specular_reflectance: scaled(specular_reflectance)? },
            MicroBsdf::Diffuse { reflectance } => MicroBsdf::Diffuse { reflectance: scaled(reflectance)? },
        })
    }
}

/// How visible normals are sampled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum VndfSampling {
    /// The distribution's exact sampler (all three NDFs have one).
    Exact,
    /// The Beckmann + uniform-hemisphere mixture of Eq. 40 (generalized NDF, specular flakes).
    Mixture(BeckmannUniformMixture),
    /// `D(m)(m·n)` + uniform-hemisphere mixture of seeds/001 Appendix B (height fields).
    NormalMixture(NormalUniformMixture),
}

/// A sampled scattering direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhaseSample {
    /// The new propagation direction (pointing away from the event).
    pub wo: DVec3,
    /// `p(wi, wo) / pdf`, the throughput factor.
    pub weight: Rgb,
    /// Solid-angle density of `wo`.
    pub pdf: f64,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MacrofacetPhase {
    pub ndf: Ndf,
    pub micro_bsdf: MicroBsdf,
    pub sampling: VndfSampling,
}

/// Mirror reflection of `wi` about `m`.
pub fn reflect(wi: DVec3, m: DVec3) -> DVec3 {
    2.0 * wi.dot(m) * m - wi
}

impl MacrofacetPhase {
    /// `p(wi, wo)` per channel (includes the flake albedo: `sigma_s = sigma_t`, Eq. 6).
    pub fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        match self.micro_bsdf {
            MicroBsdf::Diffuse { reflectance } => {
                let p = self.diffuse_lobe_integral(wi, wo);
                reflectance.map(|r| r * p)
            }
            _ => {
                let Some((m, cos)) = half_vector(wi, wo) else { return [0.0; 3] };
                let area = self.ndf.projected_area(wi);
                if area <= 0.0 {
                    return [0.0; 3];
                }
                let f = self.micro_bsdf.specular(cos).unwrap_or([0.0; 3]);
                let p = self.ndf.d(m) / (4.0 * area);
                f.map(|x| x * p)
            }
        }
    }

    /// [`Self::eval`] and [`Self::pdf`] together: for diffuse flakes both are the same
    /// quadrature, computed once (Mitsuba 3's `eval_pdf`).
    pub fn eval_pdf(&self, wi: DVec3, wo: DVec3) -> (Rgb, f64) {
        match self.micro_bsdf {
            MicroBsdf::Diffuse { reflectance } => {
                let p = self.diffuse_lobe_integral(wi, wo);
                (reflectance.map(|r| r * p), p)
            }
            _ => (self.eval(wi, wo), self.pdf(wi, wo)),
        }
    }

    /// Density of [`Self::sample`] per solid angle of `wo`.
    pub fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        match self.micro_bsdf {
            MicroBsdf::Diffuse { .. } => self.diffuse_lobe_integral(wi, wo),
            _ => {
                let Some((m, cos)) = half_vector(wi, wo) else { return 0.0 };
                self.pdf_normal(wi, m) / (4.0 * cos)
            }
        }
    }

    /// Samples `wo` with [`PHASE_SAMPLE_DIMENSIONS`] uniforms in `[0, 1)`. `None` when nothing is
    /// visible from `wi` or the sample is degenerate (probability zero for valid input).
    pub fn sample(&self, wi: DVec3, u: [f64; PHASE_SAMPLE_DIMENSIONS]) -> Option<PhaseSample> {
        let u_normal = [u[0], u[1], u[2]];
        match self.micro_bsdf {
            MicroBsdf::Diffuse { reflectance } => {
                let m = self.ndf.sample_visible(wi, u_normal)?;
                let wo = cosine_around(m, u[3], u[4]);
                let pdf = self.diffuse_lobe_integral(wi, wo);
                // Exact: m ~ D_wi and wo ~ cos/π about m reproduce p/albedo, so the weight is the
                // albedo; `pdf` is the quadrature estimate used only for MIS.
                Some(PhaseSample { wo, weight: reflectance, pdf })
            }
            _ => {
                let m = match self.sampling {
                    VndfSampling::Exact => self.ndf.sample_visible(wi, u_normal)?,
                    VndfSampling::Mixture(mix) => mix.sample(wi, u_normal)?,
                    VndfSampling::NormalMixture(mix) => mix.sample(&self.ndf, wi, u_normal)?,
                };
                let cos = wi.dot(m);
                if cos <= 0.0 {
                    return None;
                }
                let wo = reflect(wi, m).try_normalize()?;
                let f = self.micro_bsdf.specular(cos)?;
                let pdf = self.pdf_normal(wi, m) / (4.0 * cos);
                if !(pdf > 0.0) {
                    return None;
                }
                let weight = match self.sampling {
                    // eval/pdf = F · sampling_area/area: F itself unless Λ is a model.
                    VndfSampling::Exact if self.ndf.lambda_is_projected_area() => f,
                    VndfSampling::Exact => {
                        let ratio = self.ndf.sampling_projected_area(wi) / self.ndf.projected_area(wi);
                        f.map(|x| x * ratio)
                    }
                    VndfSampling::Mixture(_) | VndfSampling::NormalMixture(_) => {
                        let value = self.ndf.d(m) / (4.0 * self.ndf.projected_area(wi));
                        f.map(|x| x * value / pdf)
                    }
                };
                Some(PhaseSample { wo, weight, pdf })
            }
        }
    }

    /// Density of the normal sampler in use, per solid angle of `m`.
    fn pdf_normal(&self, wi: DVec3, m: DVec3) -> f64 {
        match self.sampling {
            VndfSampling::Exact => self.ndf.pdf_visible(wi, m),
            VndfSampling::Mixture(mix) => mix.pdf(wi, m),
            VndfSampling::NormalMixture(mix) => mix.pdf(&self.ndf, wi, m),
        }
    }

    /// `∫ D_wi(m) <wo, m> / π dm`, the diffuse-flake phase function without its albedo,
    /// by a fixed quasi-Monte Carlo rule over the exact vNDF sampler (additive recurrence with
    /// the generalized golden ratio, Roberts 2018). Deterministic; the integrand is continuous,
    /// so the error decays roughly like 1/N.
    fn diffuse_lobe_integral(&self, wi: DVec3, wo: DVec3) -> f64 {
        // 1/φ3, 1/φ3², 1/φ3³ with φ3 the plastic number's 3-D analogue (x⁴ = x + 1).
        const ALPHA: [f64; 3] = [0.819_172_513_396_164_4, 0.671_043_606_703_789_2, 0.549_700_477_901_970_4];
        let mut sum = 0.0;
        for i in 0..DIFFUSE_EVAL_POINTS {
            let u = [0, 1, 2].map(|c| (0.5 + ALPHA[c] * i as f64).fract());
            if let Some(m) = self.ndf.sample_visible(wi, u) {
                sum += wo.dot(m).max(0.0);
            }
        }
        sum * FRAC_1_PI / DIFFUSE_EVAL_POINTS as f64
    }
}

/// The half vector of a reflection and `wi·m`; `None` for back-to-back directions.
fn half_vector(wi: DVec3, wo: DVec3) -> Option<(DVec3, f64)> {
    let m = (wi + wo).try_normalize()?;
    let cos = wi.dot(m);
    (cos > 0.0).then_some((m, cos))
}

/// Cosine-weighted direction about `n` (Malley's method).
fn cosine_around(n: DVec3, u1: f64, u2: f64) -> DVec3 {
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    let (s, t) = n.any_orthonormal_pair();
    let z = (1.0 - u1).max(0.0).sqrt();
    s * (r * phi.cos()) + t * (r * phi.sin()) + n * z
}
