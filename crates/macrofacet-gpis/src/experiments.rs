//! Estimators built on [`GpisTracer`]: realization transmittance curves (seeds/000 Fig. 7),
//! visible normals at the first crossing (seeds/000 Fig. 10, seeds/004 Eq. 19 and Fig. 11–12),
//! and a mirror-flake random walk (the GPIS analogue of [`crate::slab::random_walk`]).

use super::{Crossing, GpisTracer, MeanSdf, Memory, StartState, Trace};
use macrofacet::error::Result;
use macrofacet::field::MediumField;
use glam::DVec3;

/// A realization estimate of `T(t) = P(no entering crossing on (0, t] | f(o) > 0)`.
#[derive(Clone, Debug, PartialEq)]
pub struct TransmittanceEstimate {
    /// The distances, as given.
    pub distances: Vec<f64>,
    /// Fraction of realizations without a crossing up to each distance.
    pub transmittance: Vec<f64>,
    /// Binomial standard error `√(T(1−T)/N)` of each value.
    pub standard_error: Vec<f64>,
    /// Realizations whose march was exhausted or met a non-finite mean (counted as not
    /// crossed); 0 in normal use.
    pub exhausted: usize,
}

/// Traces `realizations` independent rays from `origin` along `d` with an uncorrelated start
/// ([`StartState::Uncorrelated`], i.e. conditioned on `f(o) > 0` as the macrofacet transmittance
/// `(Φ(f1/σ)/Φ(f0/σ))^{1+Λ}` is) up to the largest distance, and returns the fraction that has not
/// crossed at each of `distances`.
pub fn transmittance_curve<M: MeanSdf, F: MediumField>(
    tracer: &GpisTracer<'_, M, F>,
    origin: DVec3,
    d: DVec3,
    distances: &[f64],
    realizations: usize,
    uniform: &mut impl FnMut() -> f64,
) -> Result<TransmittanceEstimate> {
    let t_max = distances.iter().copied().fold(0.0f64, f64::max);
    let mut survived = vec![0usize; distances.len()];
    let mut exhausted = 0;
    for _ in 0..realizations {
        let t_hit = match tracer.trace(origin, d, t_max, &StartState::Uncorrelated, uniform)? {
            Trace::Hit(c) => c.t,
            Trace::Miss => f64::INFINITY,
            Trace::Exhausted { .. } | Trace::InvalidMean { .. } => {
                exhausted += 1;
                f64::INFINITY
            }
        };
        for (s, &t) in survived.iter_mut().zip(distances) {
            if t_hit > t {
                *s += 1;
            }
        }
    }
    let n = realizations.max(1) as f64;
    let transmittance: Vec<f64> = survived.iter().map(|&s| s as f64 / n).collect();
    let standard_error = transmittance.iter().map(|&p| (p * (1.0 - p) / n).sqrt()).collect();
    Ok(TransmittanceEstimate { distances: distances.to_vec(), transmittance, standard_error, exhausted })
}

/// The normals at the first crossing of `rays` independent rays from `origin` along `d`
/// (uncorrelated start): samples of the GPIS vNDF `D_v(n | −d)` of seeds/004 Eq. 19. Rays
/// without a crossing contribute nothing.
pub fn visible_normals<M: MeanSdf, F: MediumField>(
    tracer: &GpisTracer<'_, M, F>,
    origin: DVec3,
    d: DVec3,
    rays: usize,
    uniform: &mut impl FnMut() -> f64,
) -> Result<Vec<DVec3>> {
    let mut normals = Vec::with_capacity(rays);
    for _ in 0..rays {
        if let Some(c) = tracer.first_crossing(origin, d, f64::INFINITY, &StartState::Uncorrelated, uniform)? {
            normals.push(c.normal);
        }
    }
    Ok(normals)
}

/// The end of a [`mirror_random_walk`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GpisWalk {
    /// Left along `wo` (pointing away from the surface) after `bounces` reflections.
    Escaped { wo: DVec3, bounces: u32 },
    /// Hit the bounce cap, or a march was exhausted or met a non-finite mean.
    Lost { bounces: u32 },
}

/// A path in a GPIS with perfect-mirror micro-BSDF: the ray starts at `origin` (free space,
/// uncorrelated) travelling along `−wi`, reflects about the sampled normal at each crossing
/// (`d' = d − 2 (d·n) n`) and continues from the crossing under `memory` (seeds/004 Alg. 1 with
/// a mirror `sampleDirection`), until it escapes the envelope.
pub fn mirror_random_walk<M: MeanSdf, F: MediumField>(
    tracer: &GpisTracer<'_, M, F>,
    origin: DVec3,
    wi: DVec3,
    memory: Memory,
    max_bounces: u32,
    uniform: &mut impl FnMut() -> f64,
) -> Result<GpisWalk> {
    let mut d = -wi;
    let mut o = origin;
    let mut state = StartState::Uncorrelated;
    for bounces in 0..=max_bounces {
        let c: Crossing = match tracer.trace(o, d, f64::INFINITY, &state, uniform)? {
            Trace::Hit(c) => c,
            Trace::Miss => return Ok(GpisWalk::Escaped { wo: d, bounces }),
            Trace::Exhausted { .. } | Trace::InvalidMean { .. } => return Ok(GpisWalk::Lost { bounces }),
        };
        if bounces == max_bounces {
            break;
        }
        d = (d - 2.0 * d.dot(c.normal) * c.normal).normalize();
        o = c.point;
        state = StartState::after(&c, memory);
    }
    Ok(GpisWalk::Lost { bounces: max_bounces })
}
