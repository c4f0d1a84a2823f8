//! The isotropic Generalized Trowbridge–Reitz distribution (Burley 2012; seeds/001 Appendix A):
//! a height-field NDF whose tail exponent `γ` reaches from heavier-than-GGX tails (`γ < 2`,
//! `γ = 1` is Berry's distribution, `γ = 3/2` Henyey–Greenstein at half angles) through GGX
//! (`γ = 2`) to lighter tails (`γ > 2`). Anisotropy and every other tangent-plane transform come
//! from [`super::Ltmd`] (seeds/001 Eq. 22), since GTR is shape-variant for `γ ≠ 2`.
//!
//! `D(m) = c / (1 − k cos²θ_m)^γ` with `k = 1 − α²` and the normalisation `c` of seeds/001 Eq. 32, which
//! is written as `c = ex(L) / (π ex((1 − γ) L))`, `ex(y) = expm1(y)/y`, `L = ln α²`, so that
//! the Berry limit `γ = 1` (seeds/001 Eq. 33) and `α = 1` (the uniform `D = 1/π`) are evaluated without
//! 0/0.
//!
//! **Exact Smith Λ.** For `0 < γ < 2` the generalized Stieltjes identity
//! `y^{−γ} = ∫_0^∞ t^{1−γ} (t + y)^{−2} dt / B(2 − γ, γ)` with `y = 1 − k cos²θ` writes GTR as a
//! positive continuous mixture of isotropic GGX distributions of roughness
//! `β_t² = (α² + t)/(1 + t)`, between `α` and 1. With `n = 4` instead of 2 the same identity
//! writes `2 < γ < 4` as a mixture of GTR_4 distributions, whose Λ is closed-form (seeds/001 Eq. 39).
//! Smith's Λ is linear in `D` (it is a projected area), so the exact projected area is the same
//! mixture of closed forms. In `x = ln β²` the mixing density is a Jacobi weight (Beta-type end
//! singularities with exponents `n − 1 − γ` at `β = α` and `γ − 1` at `β = 1`) times a smooth
//! factor, and the closed forms are analytic in a strip of half-width π around the real axis,
//! so Gauss–Jacobi quadrature (Golub–Welsch) converges geometrically: 20 nodes
//! reproduce the projected area to ~1e-11 relative for `α >= 0.01` (tests/ndf.rs checks it
//! against direct quadrature of `∫ <w, m> D dm`). `γ = 2` and `γ = 4` are closed forms.
//!
//! **Dimov's Λ** (seeds/001 Eqs. 34–39): the closed forms at `γ ∈ {0, 1, 2, 3, 4}` and a natural cubic
//! spline in `γ` between them. Exact at integer `γ`, an approximation otherwise; a medium whose
//! Λ is not the projected area of its `D` does not conserve energy (the white furnace measures
//! it, tests/slab.rs). Selected by [`GtrLambda::Dimov`]; the default is [`GtrLambda::Exact`].
//!
//! **Visible normals, exact.** `γ < 2`: draw the mixture's `β` from its density weighted by
//! `projected_area_β(wi)` (rejection from a piecewise power-law envelope in `t`), then a GGX
//! visible normal of roughness `β` (Heitz 2018) — an exact sample of `<wi, m> D(m)`. `γ > 2`:
//! rejection from the visible normals of a GGX whose roughness minimises the bound
//! `K = max D/D_GGX` (closed-form stationary point). Both continue, when a try is rejected, with
//! a PCG32 seeded from the bits of `u` (as pbrt-v4's stochastic BSDFs do), so the sample is a
//! deterministic function of `u`. After 48 rejections, or from the start where more than 32
//! tries are expected (light tails seen from below), an exact numerical inversion of the vNDF in
//! `(cos θ_m, φ)` takes over, which keeps the output exact (an accepted try is exact whatever
//! its index).

mod gauss_jacobi;
mod lambda;
mod sampling;

use super::MicrofacetDistribution;
use crate::error::{check_positive, Error, ErrorKind, Result};
use glam::DVec3;
use lambda::{area_from_excess, dimov_excess, natural_spline_weights, relative_expm1, ProjectedAreaMixture};
use sampling::VisibleSampler;
use std::f64::consts::PI;

/// The largest tail exponent: the exact Λ uses GTR_4 as its mixture base above 2, and Dimov's
/// closed forms stop at 4 (seeds/001 Appendix A).
const MAX_GAMMA: f64 = 4.0;

/// Which Smith Λ the distribution reports (and hence the medium's extinction and phase
/// normalisation use).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GtrLambda {
    /// The projected area of `D` itself, by the Gauss–Jacobi mixture quadrature.
    Exact,
    /// Dimov's closed forms at integer `γ`, natural cubic spline in between (seeds/001 Eqs. 34–39).
    Dimov,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gtr {
    pub alpha: f64,
    pub gamma: f64,
    pub lambda: GtrLambda,
    /// `c` of seeds/001 Eq. 32.
    norm: f64,
    /// `k = 1 − α²`, formed as `−expm1(ln α²)` (exact near `α = 1`).
    k: f64,
    ln_alpha2: f64,
    mixture: ProjectedAreaMixture,
    /// Natural-spline weights of Dimov's five closed forms at this `γ`.
    dimov_weights: [f64; 5],
    sampler: VisibleSampler,
    /// `∫ D dm`, a bound of `|∇_w ∫ <w, m> D dm|` (the gradient is `∫_{w·m>0} m D dm`).
    total_mass: f64,
}

impl Gtr {
    /// Isotropic GTR with roughness `alpha > 0` and tail `gamma ∈ (0, 4]`, Λ chosen by `lambda`.
    pub fn new(alpha: f64, gamma: f64, lambda: GtrLambda) -> Result<Gtr> {
        let alpha = check_positive("alpha", alpha, false)?;
        if !(gamma > 0.0 && gamma <= MAX_GAMMA) {
            return Err(Error::new(
                ErrorKind::InvalidValue,
                format!("parameter \"gamma\" must lie in (0, {MAX_GAMMA}], got {gamma}"),
            ));
        }
        let ln_alpha2 = 2.0 * alpha.ln();
        let k = -ln_alpha2.exp_m1();
        // seeds/001 Eq. 32: c = (γ−1)(α²−1) / (π (1 − α^{2(1−γ)})), regrouped as the product of two
        // functions that are 1 at 0 (seeds/001 Eq. 33 is the x -> 0 limit, α = 1 the L -> 0 limit).
        let norm = relative_expm1(ln_alpha2) / relative_expm1((1.0 - gamma) * ln_alpha2) / PI;
        let mixture = ProjectedAreaMixture::new(alpha, gamma);
        let mut gtr = Gtr {
            alpha,
            gamma,
            lambda,
            norm,
            k,
            ln_alpha2,
            mixture,
            dimov_weights: natural_spline_weights(gamma),
            sampler: VisibleSampler::Ggx,
            total_mass: 0.0,
        };
        gtr.total_mass = gtr.integrate_d_over_hemisphere();
        gtr.sampler = VisibleSampler::new(&gtr);
        Ok(gtr)
    }

    /// `D` as a function of `cos² θ_m` (upper hemisphere).
    fn d_of_cos2(&self, cos2: f64) -> f64 {
        self.norm * (1.0 - self.k * cos2).powf(-self.gamma)
    }

    /// `∫ D dm = 2π ∫_0^1 D(μ) dμ` by Gauss–Legendre on panels graded toward `μ = 1`, where
    /// the peak of width ~α sits.
    fn integrate_d_over_hemisphere(&self) -> f64 {
        // Panel edges in y = 1 − μ: 0, h, 2h, 4h, ... up to 1, h = min(α, 1)² / 8.
        let mut edges = vec![0.0];
        let mut h = self.alpha.min(1.0).powi(2) / 8.0;
        while h < 1.0 {
            edges.push(h);
            h *= 2.0;
        }
        edges.push(1.0);
        let mut sum = 0.0;
        for e in edges.windows(2) {
            let (mid, half) = (0.5 * (e[0] + e[1]), 0.5 * (e[1] - e[0]));
            for &(x, w) in &GL8 {
                for y in [mid - half * x, mid + half * x] {
                    let mu = 1.0 - y;
                    sum += half * w * self.d_of_cos2(mu * mu);
                }
            }
        }
        2.0 * PI * sum
    }

    /// `Λ(w) cos θ_w` seen from above at `μ = cot θ_w`, divided by `sin θ_w`: the "excess"
    /// `e(μ) = μ Λ(μ)` of the chosen Λ (finite at the horizon `μ = 0`).
    fn excess(&self, mu: f64) -> f64 {
        match self.lambda {
            GtrLambda::Exact => self.mixture.excess(mu),
            GtrLambda::Dimov => dimov_excess(self.alpha, self.ln_alpha2, &self.dimov_weights, mu),
        }
    }

    /// The exact projected area `∫ <w, m> D dm` whatever Λ the distribution reports: the
    /// normalisation of the visible normals that [`MicrofacetDistribution::sample_visible`]
    /// draws.
    pub fn exact_projected_area(&self, w: DVec3) -> f64 {
        area_from_excess(w, |mu| self.mixture.excess(mu))
    }

    /// Dimov's Λ at `w` (whatever `self.lambda` says), for comparisons.
    pub fn dimov_lambda(&self, w: DVec3) -> f64 {
        area_from_excess(-w, |mu| dimov_excess(self.alpha, self.ln_alpha2, &self.dimov_weights, mu)) / w.z
    }

    /// `∫ D dm`: bounds the gradient of the projected area (the tracker's Lipschitz constant).
    pub fn total_mass(&self) -> f64 {
        self.total_mass
    }
}

impl MicrofacetDistribution for Gtr {
    /// seeds/001 Eq. 32 (seeds/001 Eq. 33 at `γ = 1`) for `m_z > 0`.
    fn d(&self, m: DVec3) -> f64 {
        if m.z <= 0.0 {
            return 0.0;
        }
        self.d_of_cos2(m.z * m.z)
    }

    fn projected_area(&self, w: DVec3) -> f64 {
        area_from_excess(w, |mu| self.excess(mu))
    }

    fn sampling_projected_area(&self, w: DVec3) -> f64 {
        self.exact_projected_area(w)
    }

    /// Exact (module notes): see [`sampling`].
    fn sample_visible(&self, wi: DVec3, u: [f64; 3]) -> Option<DVec3> {
        let m = self.sampler.sample(self, wi, u)?;
        (wi.dot(m) > 0.0).then_some(m)
    }

    /// `m ∝ D(m) (m·n)` (Burley 2012): `cos²θ_m` inverts `F(x) = [1 − (1 − kx)^{1−γ}] /
    /// [1 − α^{2(1−γ)}]`, written with `expm1`/`ln_1p` so that `γ = 1` and `α = 1` are exact.
    fn sample_normal(&self, u: [f64; 2]) -> Option<DVec3> {
        let e = 1.0 - self.gamma;
        // ln(1 − k x) = ln(1 + u (α^{2e} − 1)) / e, with the e -> 0 limit u ln α².
        let ln_y = if e.abs() < 1e-12 { u[0] * self.ln_alpha2 } else { (u[0] * (e * self.ln_alpha2).exp_m1()).ln_1p() / e };
        let cos2 = if self.k == 0.0 { u[0] } else { (-ln_y.exp_m1() / self.k).clamp(0.0, 1.0) };
        let (sin, cos) = ((1.0 - cos2).max(0.0).sqrt(), cos2.sqrt());
        let phi = 2.0 * PI * u[1];
        DVec3::new(sin * phi.cos(), sin * phi.sin(), cos).try_normalize()
    }
}

/// Gauss–Legendre, 8 nodes: the positive abscissae and their weights.
const GL8: [(f64, f64); 4] = [
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
];
