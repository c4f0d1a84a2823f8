//! Random walks in a semi-infinite planar macrofacet slab: the medium fills `f <= kσ` below a
//! plane, with `f` the height above the mean surface. This is the setting of microfacet theory's
//! Smith masking (seeds/002 §3), the white-furnace test, and the slab BRDF that the macrofacet
//! shell produces on a locally flat surface (its multiple scattering included).
//!
//! Directions follow the crate convention: `wi` points toward the light (the ray enters along
//! `-wi`), escaped directions point away from the slab.

use macrofacet::medium::{FreeFlight, MacrofacetMedium};
use macrofacet::phase::PHASE_SAMPLE_DIMENSIONS;
use macrofacet::Rgb;
use glam::DVec3;

/// The end of one random walk.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum WalkOutcome {
    /// Left the slab upward along `wo` with throughput `weight` after `scatterings` events.
    Escaped { wo: DVec3, weight: Rgb, scatterings: u32 },
    /// Terminated by Russian roulette (an unbiased estimate of absorption).
    Absorbed { scatterings: u32 },
    /// The phase function could not continue (nothing visible), or the walk hit the event cap.
    Lost { scatterings: u32 },
}

/// Follows light entering at the top face from direction `wi` (`wi.z > 0`) until it leaves.
/// `uniform` supplies numbers in `[0, 1)`.
pub fn random_walk(
    medium: &MacrofacetMedium,
    wi: DVec3,
    max_scatterings: u32,
    mut uniform: impl FnMut() -> f64,
) -> WalkOutcome {
    walk_from(medium, medium.height.top(), -wi, max_scatterings, &mut uniform, |_, _, _| {})
}

/// The walk from height `f` along `d`; `on_event(f, wi_event, weight)` sees every scattering
/// event before its direction is sampled (used by the collision estimators below).
pub fn walk_from(
    medium: &MacrofacetMedium,
    mut f: f64,
    mut d: DVec3,
    max_scatterings: u32,
    uniform: &mut impl FnMut() -> f64,
    mut on_event: impl FnMut(f64, DVec3, Rgb),
) -> WalkOutcome {
    let mut weight: Rgb = [1.0; 3];
    for scatterings in 0..=max_scatterings {
        match medium.sample_free_flight(f, d, f64::INFINITY, uniform()) {
            FreeFlight::Pass => return WalkOutcome::Escaped { wo: d, weight, scatterings },
            FreeFlight::Scatter { t } => f += t * d.z,
        }
        if scatterings == max_scatterings {
            break;
        }
        on_event(f, -d, weight);
        let u: [f64; PHASE_SAMPLE_DIMENSIONS] = std::array::from_fn(|_| uniform());
        let Some(s) = medium.phase.sample(-d, u) else {
            return WalkOutcome::Lost { scatterings: scatterings + 1 };
        };
        weight = [0, 1, 2].map(|c| weight[c] * s.weight[c]);
        // Russian roulette once the throughput has dropped below 1 (absorbing flakes): survive
        // with probability max(weight) and compensate. Unbiased; it keeps walks in absorbing,
        // nearly isotropic slabs from wandering for thousands of events.
        let survival = weight.iter().cloned().fold(0.0, f64::max);
        if survival < 1.0 {
            if uniform() >= survival {
                return WalkOutcome::Absorbed { scatterings: scatterings + 1 };
            }
            weight = weight.map(|w| w / survival);
        }
        d = s.wo;
    }
    WalkOutcome::Lost { scatterings: max_scatterings }
}

/// One-sample estimate of the slab's reflected density toward `wo`, `f_r(wi, wo) cos θ_o`
/// (per steradian, per unit incident power): at every event the walk adds
/// `weight · p(wi_event, wo) · T(f → top along wo)` (a next-event / collision estimator).
/// Reciprocity of the slab BRDF means `estimate(wi, wo)/cos θ_o = estimate(wo, wi)/cos θ_i`.
pub fn reflected_density(
    medium: &MacrofacetMedium,
    wi: DVec3,
    wo: DVec3,
    max_scatterings: u32,
    mut uniform: impl FnMut() -> f64,
) -> Rgb {
    let mut total = [0.0; 3];
    walk_from(medium, medium.height.top(), -wi, max_scatterings, &mut uniform, |f, wi_event, weight| {
        let p = medium.phase.eval(wi_event, wo);
        let t = medium.transmittance(f, wo, f64::INFINITY);
        for c in 0..3 {
            total[c] += weight[c] * p[c] * t;
        }
    });
    total
}
