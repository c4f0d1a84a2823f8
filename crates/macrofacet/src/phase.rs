//! The macrofacet phase function, seeds/000 Eq. 11–12, with a choice of micro-BSDF on the
//! flakes.
//!
//! Direction convention (Mitsuba 3's names): `wi` and `wo` both point *away* from the scattering
//! point. A ray travelling along `d` that scatters has `wi = -d` (pbrt-v4 calls this vector `wo`);
//! the sampled `wo` is the new propagation direction. All vectors are in the local frame (normal = `+z`).
//!
//! The flakes are one-sided (seeds/002 §4.1): `p(wi, wo) = F(wi·m) D_wi(m) / (4 |wi·m|)` with
//! the half vector `m = (wi + wo)/|wi + wo|` and the visible normals `D_wi` of seeds/000 Eq. 12, so
//! `p(wi, wo) = F D(m) / (4 σ(-wi))`. Reciprocity holds for the BRDF that emerges from a slab,
//! not event by event.

use crate::error::{Error, ErrorKind, Result};
use crate::ndf::{BeckmannUniformMixture, MicrofacetDistribution, Ndf, NormalUniformMixture};
use crate::fresnel::fresnel_conductor_rgb;
use crate::Rgb;
use glam::DVec3;
use std::f64::consts::{FRAC_1_PI, PI};

/// How many uniform random numbers [`MacrofacetPhase::sample`] consumes: three for the visible
/// normal of a specular flake; for a diffuse flake the first picks one of the rule's normals and
/// the last two the cosine lobe about it.
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
    pub fn specular(&self, cos_i: f64) -> Option<Rgb> {
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
    /// The Beckmann + uniform-hemisphere mixture of seeds/000 Eq. 40 (generalized NDF, specular flakes).
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
    /// `p(wi, wo)` per channel (includes the flake albedo: `sigma_s = sigma_t`, seeds/000 Eq. 6).
    pub fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        match self.micro_bsdf {
            MicroBsdf::Diffuse { reflectance } => {
                let p = self.diffuse_lobe_integral(wi, wo);
                reflectance.map(|r| r * p)
            }
            _ => self.specular_lobe(wi, wo).0,
        }
    }

    /// A specular flake's `p(wi, wo) = F D(m) / (4 σ(wi))` per channel, with `D(m) / (4 σ(wi))`
    /// (the density of exact visible-normal sampling); zero where `wi` sees no flake or the
    /// directions are back to back.
    /// (`D(m)` first: where it is zero, as for a height field's `m` below the horizon, neither
    /// the projected area nor the Fresnel term is needed.)
    fn specular_lobe(&self, wi: DVec3, wo: DVec3) -> (Rgb, f64) {
        let Some((m, cos)) = half_vector(wi, wo) else { return ([0.0; 3], 0.0) };
        let d = self.ndf.d(m);
        let Some(area) = (d > 0.0).then(|| self.ndf.visible_area(wi)).flatten() else { return ([0.0; 3], 0.0) };
        let p = d / (4.0 * area);
        (self.micro_bsdf.specular(cos).unwrap_or([0.0; 3]).map(|x| x * p), p)
    }

    /// [`Self::eval`] and [`Self::pdf`] together (Mitsuba 3's `eval_pdf`): for diffuse flakes both
    /// are the same quadrature, for specular flakes sampled exactly the same `D(m) / (4 σ(wi))`;
    /// each computed once.
    pub fn eval_pdf(&self, wi: DVec3, wo: DVec3) -> (Rgb, f64) {
        match self.micro_bsdf {
            MicroBsdf::Diffuse { reflectance } => {
                let p = self.diffuse_lobe_integral(wi, wo);
                (reflectance.map(|r| r * p), p)
            }
            // Exact sampling with the trait's sampling area (the projected area): the lobe's
            // density is the pdf, bit for bit that of `pdf`.
            _ if self.sampling == VndfSampling::Exact && matches!(self.ndf, Ndf::Beckmann(_) | Ndf::Ggx(_) | Ndf::Gpss(_) | Ndf::GpssMatrix(_)) => self.specular_lobe(wi, wo),
            _ => (self.eval(wi, wo), self.pdf(wi, wo)),
        }
    }

    /// Density of [`Self::sample`] per solid angle of `wo`.
    pub fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        match self.micro_bsdf {
            MicroBsdf::Diffuse { .. } => self.diffuse_lobe_integral(wi, wo),
            _ => {
                let Some((m, cos)) = half_vector(wi, wo) else { return 0.0 };
                match self.sampling {
                    // D_wi(m) / (4 wi·m) (seeds/000 Eq. 12 and the reflection's Jacobian) with wi·m
                    // cancelled: forming wi·m D(m) first underflows for grazing m, where the
                    // result is an ordinary number (found by fuzzing: eval/pdf off by 1e-3).
                    // The area is the one the sampler normalises by (it differs from the
                    // projected area only where Λ is a model: GTR with Dimov's Λ).
                    VndfSampling::Exact => {
                        let area = self.ndf.sampling_projected_area(wi);
                        if area >= f64::MIN_POSITIVE {
                            self.ndf.d(m) / (4.0 * area)
                        } else {
                            0.0
                        }
                    }
                    VndfSampling::Mixture(mix) => mix.pdf(wi, m) / (4.0 * cos),
                    VndfSampling::NormalMixture(mix) => mix.pdf(&self.ndf, wi, m) / (4.0 * cos),
                }
            }
        }
    }

    /// Samples `wo` with [`PHASE_SAMPLE_DIMENSIONS`] uniforms in `[0, 1)`. `None` when nothing is
    /// visible from `wi` or the sample is degenerate (probability zero for valid input).
    /// [`Self::sample_direction`] followed by [`Self::sample_record`].
    pub fn sample(&self, wi: DVec3, u: [f64; PHASE_SAMPLE_DIMENSIONS]) -> Option<PhaseSample> {
        self.sample_record(wi, self.sample_direction(wi, u)?)
    }

    /// The direction part of [`Self::sample`]: `wo` drawn with density [`Self::pdf`].
    pub fn sample_direction(&self, wi: DVec3, u: [f64; PHASE_SAMPLE_DIMENSIONS]) -> Option<DVec3> {
        let u_normal = [u[0], u[1], u[2]];
        match self.micro_bsdf {
            MicroBsdf::Diffuse { .. } => {
                // One of the rule's normals, chosen by u[0], and a cosine lobe about it: the
                // density of `wo` is then exactly the rule's `p` (see `diffuse_lobe_integral`).
                let i = ((u[0] * DIFFUSE_EVAL_POINTS as f64) as usize).min(DIFFUSE_EVAL_POINTS - 1);
                let m = self.ndf.sample_visible(wi, diffuse_rule_point(i))?;
                Some(cosine_around(m, u[3], u[4]))
            }
            _ => {
                let m = match self.sampling {
                    VndfSampling::Exact => self.ndf.sample_visible(wi, u_normal)?,
                    VndfSampling::Mixture(mix) => mix.sample(wi, u_normal)?,
                    VndfSampling::NormalMixture(mix) => mix.sample(&self.ndf, wi, u_normal)?,
                };
                (wi.dot(m) > 0.0).then(|| reflect(wi, m).try_normalize()).flatten()
            }
        }
    }

    /// The [`PhaseSample`] of a direction `wo` from [`Self::sample_direction`]: `pdf` is
    /// [`Self::pdf`]`(wi, wo)` bit for bit and `weight` is `eval(wi, wo) / pdf` (for diffuse
    /// flakes exactly the albedo, for exact sampling exactly the flake's Fresnel reflectance).
    /// `None` when that density is below the smallest normal `f64` (then it and `eval` have lost
    /// their precision, and `eval / pdf` is noise; such directions have a total probability below
    /// `4π · 2.2e-308`) or overflows (the seeds/000 Eq. 40 mixture's density diverges like `1/(wi·m)` as `wo`
    /// turns back onto `-wi`; its weight `eval/pdf` is 0 there, so no estimate changes).
    ///
    /// Everything is evaluated at `wo`, not at the normal it was sampled with: the half vector
    /// of `wo` differs from that normal by rounding (~1e-16), which changes `D` by up to 1e-6
    /// relative where its lobe is 1e-10 rad wide (issue 9 item 7), and a host must get one
    /// density for one pair of directions. A host working in another frame passes `wo` after
    /// its own round trip (the C ABI does), so that the pdf it later queries is this one.
    pub fn sample_record(&self, wi: DVec3, wo: DVec3) -> Option<PhaseSample> {
        let pdf = self.pdf(wi, wo);
        if !(pdf >= f64::MIN_POSITIVE && pdf.is_finite()) {
            return None;
        }
        let weight = match self.micro_bsdf {
            MicroBsdf::Diffuse { reflectance } => reflectance,
            _ => match self.sampling {
                // D_wi(m) / (4 cos) is the density of m ~ D_wi reflected, so p / pdf = F unless
                // Λ is a model (then p / pdf = F · sampling area / area).
                VndfSampling::Exact if self.ndf.lambda_is_projected_area() => self.micro_bsdf.specular(half_vector(wi, wo)?.1)?,
                _ => self.eval(wi, wo).map(|x| x / pdf),
            },
        };
        Some(PhaseSample { wo, weight, pdf })
    }

    /// `∫ D_wi(m) <wo, m> / π dm`, the diffuse-flake phase function without its albedo,
    /// by a fixed quasi-Monte Carlo rule over the exact vNDF sampler (additive recurrence with
    /// the generalized golden ratio, Roberts 2018). Deterministic; the integrand is continuous,
    /// so the error decays roughly like 1/N.
    ///
    /// The rule is also *the* diffuse-flake phase function of this library: `p` is a mixture of
    /// `DIFFUSE_EVAL_POINTS` clamped-cosine lobes about the rule's normals `m_i`, and
    /// [`Self::sample_direction`] draws from exactly that mixture. So eval, pdf and sample agree to the
    /// last bit, and a sampled `wo` always has `pdf > 0` (its own lobe contributes); sampling the
    /// exact `D_wi` instead could land where every `m_i` has `<wo, m_i> = 0` (issue 9 item 4).
    fn diffuse_lobe_integral(&self, wi: DVec3, wo: DVec3) -> f64 {
        let mut sum = 0.0;
        for i in 0..DIFFUSE_EVAL_POINTS {
            if let Some(m) = self.ndf.sample_visible(wi, diffuse_rule_point(i)) {
                sum += wo.dot(m).max(0.0);
            }
        }
        sum * FRAC_1_PI / DIFFUSE_EVAL_POINTS as f64
    }
}

/// Point `i` of the diffuse-flake rule in `[0, 1)³`: the additive recurrence with
/// 1/φ3, 1/φ3², 1/φ3³, φ3 being the plastic number's 3-D analogue (x⁴ = x + 1).
fn diffuse_rule_point(i: usize) -> [f64; 3] {
    const ALPHA: [f64; 3] = [0.819_172_513_396_164_4, 0.671_043_606_703_789_2, 0.549_700_477_901_970_4];
    [0, 1, 2].map(|c| (0.5 + ALPHA[c] * i as f64).fract())
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
