//! The opaque core of a closed shell: a level `f_core` so deep below the mean surface that a ray
//! from any point with `f >= f_start` has a transmittance below the smallest positive `f64` once
//! it reaches `f <= f_core`. A host may treat the core as an opaque occluder for such rays (a
//! shadow ray from a collision into a sphere's interior): their estimates would round to 0.
//!
//! Along a ray `τ = ∫ σ_t ds` with `σ_t = ρ(f) σ(d)` (seeds/000 Eq. 13, 14). A ray from `f_start`
//! to `f_core` descends through every level between them at least once, so if `σ(d) ds >= κ |df|`
//! wherever it descends, `τ >= κ ∫_{f_core}^{f_start} ρ(f) df = κ [ln Φ(f_start/σ) − ln Φ(f_core/σ)]`
//! (`ln Φ(f/σ)` is an antiderivative of Eq. 13's `ρ`; `f_start` lies below the top face, where
//! `ρ` is not cut). With `f` `L`-Lipschitz (`|∇f| <= L`):
//! - where the frame normal `n` is the direction of `∇f` (a sphere), `|df/ds| = |∇f| |d·n| <=
//!   L |d·n|` with `d·n < 0` where the ray descends, so `κ = min σ(d)/(L |d·n|)` over
//!   `d·n ∈ [−1, 0)`: about `1/L`, as a normalised distribution's projected area is at least
//!   `|d·n|` (`E[max(0, w·g)] >= w·E[g]`);
//! - otherwise (a mesh's vertex normals), `|df/ds| <= L`, and `κ = min σ(d)/L` over every
//!   direction.
//!
//! The core is where `τ` reaches [`OPAQUE_DEPTH`]. Shallower descents have the same bound, `τ >=
//! κ [ln Φ(f_from/σ) − ln Φ(f_to/σ)]` ([`descent_transmittance_bound`]): a host's Russian roulette
//! keeps such a shadow ray with that transmittance over the tracker's roulette threshold
//! ([`crate::tracking::Tracker::depth_roulette`]), before it evaluates anything for it.

use crate::height::HeightProfile;
use crate::special::{ln_normal_cdf, probit_of_ln};

/// `f_start = −START_SIGMAS σ`: a collision lies deeper with probability about `Φ(−8) ≈ 6e-16`, so
/// nearly every collision, and every point above the shell, may use the core.
pub const START_SIGMAS: f64 = 8.0;

/// The optical depth that makes a transmittance round to 0: `e^-750` is below half the smallest
/// subnormal `f64` (`2^-1075 = e^-745.13`).
pub const OPAQUE_DEPTH: f64 = 750.0;

/// The levels of an opaque core ([`opaque_core`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OpaqueCore {
    /// Rays from points with `f >= start_level` may use the core (`−`[`START_SIGMAS`]` σ`).
    pub start_level: f64,
    /// Reaching `f <= core_level`, such a ray has a transmittance below `e^-`[`OPAQUE_DEPTH`].
    pub core_level: f64,
}

/// `f_start` of a shell with heights `height`: `−`[`START_SIGMAS`]` σ`.
pub fn start_level(height: &HeightProfile) -> f64 {
    -START_SIGMAS * height.sigma
}

/// The opaque core of a stationary shell with heights `height` along whose descending rays
/// `σ(d) ds >= kappa |df|` (the module's `κ`). `None` when that gives none (`kappa` not positive,
/// or a core beyond `f64`'s range).
pub fn opaque_core(height: &HeightProfile, kappa: f64) -> Option<OpaqueCore> {
    let sigma = height.sigma;
    if !(kappa > 0.0 && sigma > 0.0) {
        return None;
    }
    let start = -START_SIGMAS;
    let target = ln_normal_cdf(start) - OPAQUE_DEPTH / kappa;
    if !target.is_finite() {
        return None;
    }
    // The quantile is accurate to ~1e-15 relative; moved down until ln Φ confirms the depth.
    let mut x = probit_of_ln(target);
    for _ in 0..8 {
        if ln_normal_cdf(x) <= target {
            let core_level = x * sigma;
            return core_level.is_finite().then_some(OpaqueCore { start_level: start_level(height), core_level });
        }
        x *= 1.0 + 1e-12;
    }
    None
}

/// An upper bound of the transmittance of a ray, in a stationary shell with heights `height`
/// and the module's rate `kappa`, whose height goes from `f_from` down to `f_to` or below:
/// `exp(−κ [ln Φ(min(f_from, top)/σ) − ln Φ(f_to/σ)])` (above the top face `ρ` is zero), 1
/// where that interval is empty or `kappa` is not positive, 0 for `f_to = −∞`. Any larger
/// `f_to` or smaller `f_from` gives a larger bound: callers round those ways.
pub fn descent_transmittance_bound(height: &HeightProfile, kappa: f64, f_from: f64, f_to: f64) -> f64 {
    if f_from.is_nan() || f_to.is_nan() {
        return 1.0;
    }
    let (from, to) = (f_from.min(height.top()), f_to);
    if !(kappa > 0.0 && to < from) {
        return 1.0;
    }
    let depth = kappa * (height.ln_cdf(from) - height.ln_cdf(to));
    // (ln Φ(−∞) = −∞: depth +∞, bound 0.)
    (-depth).exp().min(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `∫ ρ(f) df` over `[f_core, f_start]` by Gauss–Legendre panels of Eq. 13's density, against
    /// the closed form the core rests on: the quadrature checks the antiderivative, not itself.
    fn density_integral(height: &HeightProfile, lo: f64, hi: f64) -> f64 {
        const NODES: [(f64, f64); 3] = [(-0.774_596_669_241_483_4, 5.0 / 9.0), (0.0, 8.0 / 9.0), (0.774_596_669_241_483_4, 5.0 / 9.0)];
        let panels = 20_000;
        let h = (hi - lo) / panels as f64;
        (0..panels)
            .map(|i| {
                let mid = lo + (i as f64 + 0.5) * h;
                NODES.iter().map(|(x, w)| w * 0.5 * h * height.density(mid + 0.5 * h * x)).sum::<f64>()
            })
            .sum()
    }

    #[test]
    fn the_core_is_as_deep_as_the_opaque_depth_needs() {
        for (sigma, kappa) in [(1e-3, 0.97), (0.02, 0.3), (1.0, 1e-3), (1e-3, 0.085 / 2.5)] {
            let height = HeightProfile::new(sigma, 3.0).unwrap();
            let core = opaque_core(&height, kappa).unwrap();
            assert_eq!(core.start_level, -START_SIGMAS * sigma);
            let depth = kappa * density_integral(&height, core.core_level, core.start_level);
            // At least the opaque depth, and no deeper than needed (the quadrature's error ~1e-9).
            assert!((OPAQUE_DEPTH * (1.0 - 1e-9)..=OPAQUE_DEPTH * 1.001).contains(&depth), "sigma {sigma}, kappa {kappa}: depth {depth}");
        }
    }

    #[test]
    fn no_core_without_a_positive_rate() {
        let height = HeightProfile::new(1e-3, 3.0).unwrap();
        assert_eq!(opaque_core(&height, 0.0), None);
        assert_eq!(opaque_core(&height, f64::NAN), None);
        // A depth beyond f64's range (a subnormal rate): none rather than −∞.
        assert_eq!(opaque_core(&height, 1e-310), None);
    }
}
