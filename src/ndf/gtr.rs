//! The isotropic Generalized Trowbridge–Reitz distribution (Burley 2012; seeds/001 Appendix A):
//! a height-field NDF whose tail exponent `γ` reaches from heavier-than-GGX tails (`γ < 2`,
//! `γ = 1` is Berry's distribution, `γ = 3/2` Henyey–Greenstein at half angles) through GGX
//! (`γ = 2`) to lighter tails (`γ > 2`). Anisotropy and every other tangent-plane transform come
//! from [`super::Ltmd`] (seeds/001 Eq. 22), since GTR is shape-variant for `γ ≠ 2`.
//!
//! `D(m) = c / (1 − k cos²θ_m)^γ` with `k = 1 − α²` and the normalisation `c` of Eq. 32, which
//! is written as `c = ex(L) / (π ex((1 − γ) L))`, `ex(y) = expm1(y)/y`, `L = ln α²`, so that
//! the Berry limit `γ = 1` (Eq. 33) and `α = 1` (the uniform `D = 1/π`) are evaluated without
//! 0/0.
//!
//! **Exact Smith Λ.** For `0 < γ < 2` the generalized Stieltjes identity
//! `y^{−γ} = ∫_0^∞ t^{1−γ} (t + y)^{−2} dt / B(2 − γ, γ)` with `y = 1 − k cos²θ` writes GTR as a
//! positive continuous mixture of isotropic GGX distributions of roughness
//! `β_t² = (α² + t)/(1 + t)`, between `α` and 1. With `n = 4` instead of 2 the same identity
//! writes `2 < γ < 4` as a mixture of GTR_4 distributions, whose Λ is closed-form (Eq. 39).
//! Smith's Λ is linear in `D` (it is a projected area), so the exact projected area is the same
//! mixture of closed forms. In `x = ln β²` the mixing density is a Jacobi weight (Beta-type end
//! singularities with exponents `n − 1 − γ` at `β = α` and `γ − 1` at `β = 1`) times a smooth
//! factor, and the closed forms are analytic in a strip of half-width π around the real axis,
//! so Gauss–Jacobi quadrature (Golub–Welsch) converges geometrically: [`MIXTURE_NODES`] nodes
//! reproduce the projected area to ~1e-11 relative for `α >= 0.01` (tests/ndf.rs checks it
//! against direct quadrature of `∫ <w, m> D dm`). `γ = 2` and `γ = 4` are closed forms.
//!
//! **Dimov's Λ** (Eqs. 34–39): the closed forms at `γ ∈ {0, 1, 2, 3, 4}` and a natural cubic
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
//! deterministic function of `u`; after [`MAX_TRIES`] rejections (light tails seen from below)
//! they hand over to an exact numerical inversion of the vNDF in `(cos θ_m, φ)`, which keeps the
//! output exact (an accepted try is exact whatever its index).

use super::ggx::Ggx;
use super::MicrofacetDistribution;
use crate::error::{check_positive, Error, ErrorKind, Result};
use crate::rng::Pcg32;
use glam::DVec3;
use std::f64::consts::PI;

/// The largest tail exponent: the exact Λ uses GTR_4 as its mixture base above 2, and Dimov's
/// closed forms stop at 4 (seeds/001 Appendix A).
const MAX_GAMMA: f64 = 4.0;

/// Gauss–Jacobi nodes of the exact projected-area mixture (see the module notes).
const MIXTURE_NODES: usize = 20;

/// Rejection tries before a visible-normal sample falls back to [`Gtr::sample_by_inversion`].
/// Every accepted try is an exact sample whatever its index, so the fallback keeps the output
/// exact; it matters where the acceptance collapses (light tails, γ > 2, seen from below, where
/// a GGX proposal has ~1e-8 of its visible mass where GTR has its own).
const MAX_TRIES: u32 = 48;

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
    /// `c` of Eq. 32.
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
        // Eq. 32: c = (γ−1)(α²−1) / (π (1 − α^{2(1−γ)})), regrouped as the product of two
        // functions that are 1 at 0 (Eq. 33 is the x -> 0 limit, α = 1 the L -> 0 limit).
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
    /// Eq. 32 (Eq. 33 at `γ = 1`) for `m_z > 0`.
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

    fn sample_visible(&self, wi: DVec3, u: [f64; 3]) -> Option<DVec3> {
        let m = match self.sampler {
            VisibleSampler::Ggx => Ggx { alpha_u: self.alpha, alpha_v: self.alpha }.sample_visible(wi, u)?,
            VisibleSampler::GgxMixture(env) => env.sample(wi, u).or_else(|| self.sample_by_inversion(wi, u))?,
            VisibleSampler::GgxRejection { alpha, bound } => {
                // Expected tries = K A_GGX(wi) / A(wi): where they exceed 32 (light tails seen
                // from below or at grazing angles) the inversion is cheaper.
                let proposal_area = Ggx { alpha_u: alpha, alpha_v: alpha }.projected_area(wi);
                if bound * proposal_area > 32.0 * self.exact_projected_area(wi) {
                    self.sample_by_inversion(wi, u)?
                } else {
                    self.sample_by_rejection(alpha, bound, wi, u).or_else(|| self.sample_by_inversion(wi, u))?
                }
            }
        };
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

impl Gtr {
    /// Rejection from the visible normals of `GGX(alpha)` with `D <= bound · D_GGX` (`γ > 2`).
    fn sample_by_rejection(&self, alpha: f64, bound: f64, wi: DVec3, u: [f64; 3]) -> Option<DVec3> {
        let proposal = Ggx { alpha_u: alpha, alpha_v: alpha };
        let mut try_u = u;
        let mut rng: Option<Pcg32> = None;
        for _ in 0..MAX_TRIES {
            if let Some(m) = proposal.sample_visible(wi, [try_u[0], try_u[1], 0.0]) {
                if try_u[2] * bound * proposal.d(m) < self.d(m) {
                    return Some(m);
                }
            }
            let r = rng.get_or_insert_with(|| rejection_generator(&u));
            try_u = [r.next_f64(), r.next_f64(), r.next_f64()];
        }
        None
    }
}

impl Gtr {
    /// Exact visible normal by inversion in `(μ, φ)`, `μ = cos θ_m` and `φ` the azimuth about
    /// `wi`'s: with `a = wi_z μ`, `b = |wi_t| sqrt(1 − μ²)`, `<wi, m> = max(0, a + b cos φ)`, so the
    /// marginal of `μ` is `D(μ) g(μ)` with `g = ∫ <wi, m> dφ = 2(a φ0 + b sin φ0)`,
    /// `cos φ0 = −a/b` (`2πa` where `a >= b`), inverted numerically (Gauss–Legendre on panels
    /// graded toward the peak of `D` and toward the kink `a = b` at `μ = |wi_t|`, then Newton in
    /// the panel), and `φ` given `μ` inverts `a ψ + b sin ψ` (Newton). The general fallback of
    /// the rejection samplers: ~5–10 µs, exact to the quadrature (~1e-12 in the CDF).
    fn sample_by_inversion(&self, wi: DVec3, u: [f64; 3]) -> Option<DVec3> {
        let s = (wi.x * wi.x + wi.y * wi.y).sqrt();
        let ring = |mu: f64| -> f64 {
            let (a, b) = (wi.z * mu, s * (1.0 - mu * mu).max(0.0).sqrt());
            if a >= b {
                2.0 * PI * a
            } else if a <= -b {
                0.0
            } else {
                let phi0 = (-a / b).acos();
                2.0 * (a * phi0 + b * phi0.sin())
            }
        };
        let density = |mu: f64| self.d_of_cos2(mu * mu) * ring(mu);
        // Seen from below nothing with μ >= |wi_t| faces wi.
        let hi = if wi.z >= 0.0 { 1.0 } else { s.min(1.0) };
        if !(hi > 0.0) {
            return None;
        }
        let mut edges: smallvec::SmallVec<[f64; 64]> = smallvec::smallvec![0.0, hi];
        let mut push = |x: f64| {
            if x > 0.0 && x < hi {
                edges.push(x);
            }
        };
        push(s);
        // Geometric grading (ratio 4) toward the kink, to 1e-10 of the distance to the ends, and
        // around the peak of D: at the pole (width ~α² in μ) for α < 1, at the horizon (width
        // ~1/α) for α > 1.
        for j in 0..17 {
            let h = 0.25f64.powi(j);
            push(s - h * s);
            push(s + h * (1.0 - s));
        }
        for j in -5..7 {
            let h = 4f64.powi(j);
            if self.alpha < 1.0 {
                push(1.0 - self.alpha * self.alpha * h);
            } else {
                push(h / self.alpha);
            }
        }
        edges.sort_by(f64::total_cmp);
        edges.dedup();
        let panel = |lo: f64, hi: f64| -> f64 {
            let (mid, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
            GL8.iter().map(|&(x, w)| half * w * (density(mid - half * x) + density(mid + half * x))).sum()
        };
        let masses: smallvec::SmallVec<[f64; 64]> = edges.windows(2).map(|e| panel(e[0], e[1])).collect();
        let total: f64 = masses.iter().sum();
        if !(total > 0.0) {
            return None;
        }
        let mut target = u[0] * total;
        let mut i = 0;
        while i + 1 < masses.len() && target >= masses[i] {
            target -= masses[i];
            i += 1;
        }
        let (mut lo, mut hi_p) = (edges[i], edges[i + 1]);
        let start = lo;
        let mut mu = 0.5 * (lo + hi_p);
        for _ in 0..50 {
            let f = panel(start, mu) - target;
            if f > 0.0 {
                hi_p = mu;
            } else {
                lo = mu;
            }
            let p = density(mu);
            let next = if p > 0.0 { mu - f / p } else { f64::NAN };
            let next = if next > lo && next < hi_p { next } else { 0.5 * (lo + hi_p) };
            if (next - mu).abs() <= 1e-15 * (1.0 + mu) || hi_p - lo <= 1e-15 {
                mu = next;
                break;
            }
            mu = next;
        }
        // φ given μ: |φ| has the CDF a ψ + b sin ψ on [0, φ0]; u[1] picks the side.
        let (a, b) = (wi.z * mu, s * (1.0 - mu * mu).max(0.0).sqrt());
        let phi0 = if a >= b { PI } else { (-a / b).clamp(-1.0, 1.0).acos() };
        let (side, v) = if u[1] < 0.5 { (1.0, 2.0 * u[1]) } else { (-1.0, 2.0 * u[1] - 1.0) };
        let goal = v * (a * phi0 + b * phi0.sin());
        let (mut lo, mut hi_q, mut psi) = (0.0, phi0, 0.5 * phi0);
        for _ in 0..60 {
            let f = a * psi + b * psi.sin() - goal;
            if f > 0.0 {
                hi_q = psi;
            } else {
                lo = psi;
            }
            let slope = a + b * psi.cos();
            let next = if slope > 0.0 { psi - f / slope } else { f64::NAN };
            let next = if next > lo && next < hi_q { next } else { 0.5 * (lo + hi_q) };
            if (next - psi).abs() <= 1e-15 {
                psi = next;
                break;
            }
            psi = next;
        }
        let phi = wi.y.atan2(wi.x) + side * psi;
        let sin = (1.0 - mu * mu).max(0.0).sqrt();
        DVec3::new(sin * phi.cos(), sin * phi.sin(), mu).try_normalize()
    }
}

/// Gauss–Legendre, 8 nodes: the positive abscissae and their weights.
const GL8: [(f64, f64); 4] = [
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
];

/// A PCG32 seeded from the bits of the uniforms of a sample (SplitMix64 finaliser), for the
/// tries after the first of a rejection sampler.
fn rejection_generator(u: &[f64]) -> Pcg32 {
    let mut h: u64 = 0x9e37_79b9_7f4a_7c15;
    for x in u {
        h ^= x.to_bits();
        h = h.wrapping_add(0x9e37_79b9_7f4a_7c15);
        h = (h ^ (h >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        h = (h ^ (h >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        h ^= h >> 31;
    }
    Pcg32::new(h, 0x6774_72)
}

/// The projected area `∫ <w, m> D dm` of an isotropic height-field NDF from its excess
/// `e(μ) = μ Λ(μ)`, for any (not necessarily unit) `w` — the area is homogeneous of degree 1:
/// with `s = |w_t|`, `s e(w_z/s) + w_z` above and `s e(−w_z/s)` below (Eq. 39 gives the signed
/// identity `A(w) − A(−w) = w_z`).
pub(crate) fn area_from_excess(w: DVec3, excess: impl Fn(f64) -> f64) -> f64 {
    let s = (w.x * w.x + w.y * w.y).sqrt();
    if s == 0.0 {
        return w.z.max(0.0);
    }
    let mu = w.z.abs() / s;
    // Far above the pole the excess is below one ulp of w_z (e ~ 1/μ): skip it.
    let e = if mu > 1e154 { 0.0 } else { s * excess(mu) };
    if w.z >= 0.0 {
        w.z + e
    } else {
        e
    }
}

/// `e(μ) = (sqrt(β² + μ²) − μ)/2` of GGX, cancellation-free.
fn ggx_excess(beta2: f64, mu: f64) -> f64 {
    0.5 * beta2 / ((beta2 + mu * mu).sqrt() + mu)
}

/// `e(μ) = μ/S_4(μ) − μ` of GTR_4 with roughness² `a2` (seeds/001 Eq. 39), with
/// `μ³ − B³ = −a2 (μ² + μB + B²)/(μ + B)` so that nothing cancels for small `a2`.
fn gtr4_excess(a2: f64, mu: f64) -> f64 {
    let big_a = 8.0 * (a2 * a2 + a2 + 1.0);
    let b = (mu * mu + a2).sqrt();
    let b3 = b * b * b;
    let head = -big_a * mu * a2 * (mu * mu + mu * b + b * b) / (mu + b);
    let tail = 3.0 * a2 * (a2 * (5.0 * a2 * a2 + 2.0 * a2 + 1.0) + 4.0 * mu * mu * (2.0 * a2 * a2 + a2 + 1.0));
    (head + tail) / (2.0 * big_a * b3)
}

/// The exact projected area as a Gauss–Jacobi mixture of closed forms (module notes).
#[derive(Clone, Copy, Debug, PartialEq)]
struct ProjectedAreaMixture {
    /// 2: GGX components (`γ <= 2`); 4: GTR_4 components (`γ > 2`).
    base: u8,
    nodes: usize,
    beta2: [f64; MIXTURE_NODES],
    weight: [f64; MIXTURE_NODES],
}

impl ProjectedAreaMixture {
    fn new(alpha: f64, gamma: f64) -> Self {
        let mut mix = ProjectedAreaMixture { base: 2, nodes: 1, beta2: [0.0; MIXTURE_NODES], weight: [0.0; MIXTURE_NODES] };
        mix.beta2[0] = alpha * alpha;
        mix.weight[0] = 1.0;
        if gamma == 4.0 {
            mix.base = 4;
        }
        if gamma == 2.0 || gamma == 4.0 || alpha == 1.0 {
            return mix; // a single closed form (α = 1 is the uniform D for every γ)
        }
        mix.base = if gamma < 2.0 { 2 } else { 4 };
        mix.nodes = MIXTURE_NODES;
        let (beta2, weight) = mixture_nodes(alpha, gamma, mix.base, MIXTURE_NODES);
        mix.beta2.copy_from_slice(&beta2);
        mix.weight.copy_from_slice(&weight);
        mix
    }

    fn excess(&self, mu: f64) -> f64 {
        let mut sum = 0.0;
        for i in 0..self.nodes {
            let e = if self.base == 2 { ggx_excess(self.beta2[i], mu) } else { gtr4_excess(self.beta2[i], mu) };
            sum += self.weight[i] * e;
        }
        sum
    }
}

/// Nodes `β_i²` and normalised weights of the mixture `D_γ = Σ w_i D_{n, β_i}` (`n` = `base`):
/// Gauss–Jacobi in `x = ln β²` on `[ln α², 0]` (or `[0, ln α²]`), the weight's end exponents
/// `n − 1 − γ` (at `β = α`) and `γ − 1` (at `β = 1`), times the smooth factor
/// `ex(x − ln α²)^{n−1−γ} ex(x)^{γ−1} / (β² c_n(β²)/c_n-free part)` with `ex(y) = expm1(y)/y`.
/// Public to the crate so that tests can build high-order references.
pub(crate) fn mixture_nodes(alpha: f64, gamma: f64, base: u8, n: usize) -> (Vec<f64>, Vec<f64>) {
    let x_alpha = 2.0 * alpha.ln();
    let e_alpha = f64::from(base) - 1.0 - gamma;
    let e_one = gamma - 1.0;
    // Jacobi weight (1 − z)^a (1 + z)^b on [−1, 1]; z = −1 is the lower end of x.
    let (x_lo, x_hi, a, b) = if x_alpha < 0.0 { (x_alpha, 0.0, e_one, e_alpha) } else { (0.0, x_alpha, e_alpha, e_one) };
    let (z, v) = gauss_jacobi(n, a, b);
    let mut beta2 = vec![0.0; n];
    let mut weight = vec![0.0; n];
    for i in 0..n {
        let x = x_lo + (x_hi - x_lo) * 0.5 * (1.0 + z[i]);
        let p = x.exp();
        // The base's normalisation: GGX c_2 = p/π is absorbed by dp = p dx; GTR_4 leaves
        // (p² + p + 1)/p² (c_4 = 3p³/(π(p² + p + 1))).
        let extra = if base == 2 { 1.0 } else { (p * p + p + 1.0) / (p * p) };
        let smooth = relative_expm1(x - x_alpha).powf(e_alpha) * relative_expm1(x).powf(e_one) * extra;
        beta2[i] = p;
        weight[i] = v[i] * smooth;
    }
    let total: f64 = weight.iter().sum();
    weight.iter_mut().for_each(|w| *w /= total);
    (beta2, weight)
}

/// Gauss–Jacobi nodes on `(−1, 1)` for the weight `(1 − z)^a (1 + z)^b` and their weights up to
/// a common factor: Golub–Welsch (eigenvalues of the Jacobi matrix of the monic recurrence by
/// implicit QL, weights from the eigenvectors' first components).
fn gauss_jacobi(n: usize, a: f64, b: f64) -> (Vec<f64>, Vec<f64>) {
    let mut diag = vec![0.0; n];
    let mut off = vec![0.0; n];
    let ab = a + b;
    for k in 0..n {
        let kf = k as f64;
        diag[k] = if k == 0 { (b - a) / (ab + 2.0) } else { (b * b - a * a) / ((2.0 * kf + ab) * (2.0 * kf + ab + 2.0)) };
        if k + 1 < n {
            let j = kf + 1.0;
            let s = 2.0 * j + ab;
            off[k] = (4.0 * j * (j + a) * (j + b) * (j + ab) / (s * s * (s + 1.0) * (s - 1.0))).sqrt();
        }
    }
    let mut first = vec![0.0; n];
    first[0] = 1.0;
    symmetric_tridiagonal_ql(&mut diag, &mut off, &mut first);
    let weights = first.iter().map(|v| v * v).collect();
    (diag, weights)
}

/// Implicit QL with Wilkinson shifts on a symmetric tridiagonal matrix (`d` diagonal, `e`
/// sub-diagonal in `e[0..n−1]`): `d` becomes the eigenvalues and `z` (the first row of the
/// identity on entry) the first components of the eigenvectors.
fn symmetric_tridiagonal_ql(d: &mut [f64], e: &mut [f64], z: &mut [f64]) {
    let n = d.len();
    for l in 0..n {
        for _ in 0..60 {
            let mut m = l;
            while m + 1 < n {
                let dd = d[m].abs() + d[m + 1].abs();
                if e[m].abs() <= f64::EPSILON * dd {
                    break;
                }
                m += 1;
            }
            if m == l {
                break;
            }
            let mut g = (d[l + 1] - d[l]) / (2.0 * e[l]);
            let mut r = g.hypot(1.0);
            g = d[m] - d[l] + e[l] / (g + r.copysign(g));
            let (mut s, mut c, mut p) = (1.0, 1.0, 0.0);
            let mut i = m;
            let mut underflow = false;
            while i > l {
                i -= 1;
                let f = s * e[i];
                let bb = c * e[i];
                r = f.hypot(g);
                e[i + 1] = r;
                if r == 0.0 {
                    d[i + 1] -= p;
                    e[m] = 0.0;
                    underflow = true;
                    break;
                }
                s = f / r;
                c = g / r;
                g = d[i + 1] - p;
                r = (d[i] - g) * s + 2.0 * c * bb;
                p = s * r;
                d[i + 1] = g + p;
                g = c * r - bb;
                let zf = z[i + 1];
                z[i + 1] = s * z[i] + c * zf;
                z[i] = c * z[i] - s * zf;
            }
            if underflow {
                continue;
            }
            d[l] -= p;
            e[l] = g;
            e[m] = 0.0;
        }
    }
}

/// `expm1(y)/y`, 1 at 0.
fn relative_expm1(y: f64) -> f64 {
    if y.abs() < 1e-300 {
        1.0
    } else {
        y.exp_m1() / y
    }
}

/// `ln(1 + z)/z`, 1 at 0.
fn relative_ln_1p(z: f64) -> f64 {
    if z.abs() < 1e-300 {
        1.0
    } else {
        z.ln_1p() / z
    }
}

/// Dimov's `μ/S_γ(μ) − μ` (seeds/001 Eqs. 35–39 with `G1 = S`, `S = 1/(1 + Λ)`): the five
/// closed forms as `1/F_j = S_j/μ` and the natural cubic spline in `γ` through them (the paper
/// splines `S_γ`; at fixed `μ` that is the same as splining `S/μ`).
fn dimov_excess(alpha: f64, ln_alpha2: f64, weights: &[f64; 5], mu: f64) -> f64 {
    let a2 = alpha * alpha;
    let b = (mu * mu + 1.0).sqrt(); // B_1
    let a = (mu * mu + a2).sqrt(); // A_1 = A_3 = B_4
    // Each closed form as its excess e_j = F_j − μ, F_j = μ/S_j, free of cancellation:
    // Eq. 35: F_0 = (μ + sqrt(1 + μ²))/2.
    let e0 = 0.5 / (b + mu);
    // Eq. 36 regrouped in d = α² − 1 = expm1(L), L = ln α²:
    // e_1 = (d/L) / (A + B) · [1 − μ lnratio(z)/(μ + A)], z = −d/((A + B)(μ + A)).
    let d = ln_alpha2.exp_m1();
    let z = -d / ((a + b) * (mu + a));
    let e1 = relative_expm1(ln_alpha2) / (a + b) * (1.0 - mu * relative_ln_1p(z) / (mu + a));
    // Eq. 37 (GGX).
    let e2 = ggx_excess(a2, mu);
    // Eq. 38: F_3 = (α²(3α² + 1) + 2μ B_3 (μ + A_3)) / (4 B_3 A_3), B_3 = α² + 1, so
    // e_3 = α² (3α² + 1 − 2μ B_3/(μ + A_3)) / (4 B_3 A_3).
    let b3 = a2 + 1.0;
    let e3 = a2 * (3.0 * a2 + 1.0 - 2.0 * mu * b3 / (mu + a)) / (4.0 * b3 * a);
    // Eq. 39.
    let e4 = gtr4_excess(a2, mu);
    // Spline of S_j/μ = 1/F_j (the weights sum to 1): 1/F = Σ w_j/F_j, and
    // e = F − μ = (1 − μ/F) F = F Σ w_j e_j/F_j.
    let (mut inv_f, mut num) = (0.0, 0.0);
    for (e, w) in [e0, e1, e2, e3, e4].into_iter().zip(weights) {
        let f = mu + e;
        inv_f += w / f;
        num += w * e / f;
    }
    (num / inv_f).max(0.0)
}

/// Weights `ω_j(γ)` with `spline(γ) = Σ ω_j y_j` for the natural cubic spline through
/// `(j, y_j)`, `j = 0..4` (unit knot spacing).
fn natural_spline_weights(gamma: f64) -> [f64; 5] {
    // Second derivatives M_1..M_3 solve [4 1 0; 1 4 1; 0 1 4] M = 6 Δ²y, M_0 = M_4 = 0; the
    // inverse of that matrix is [15 −4 1; −4 16 −4; 1 −4 15]/56.
    let inv = [[15.0, -4.0, 1.0], [-4.0, 16.0, -4.0], [1.0, -4.0, 15.0]].map(|r| r.map(|x: f64| x / 56.0));
    // M_i = Σ_j c_ij y_j.
    let mut c = [[0.0; 5]; 5];
    for i in 0..3 {
        for r in 0..3 {
            // Δ²y at knot r+1: y_r − 2 y_{r+1} + y_{r+2}.
            c[i + 1][r] += 6.0 * inv[i][r];
            c[i + 1][r + 1] -= 12.0 * inv[i][r];
            c[i + 1][r + 2] += 6.0 * inv[i][r];
        }
    }
    let seg = (gamma.floor() as usize).min(3);
    let t = gamma - seg as f64;
    let s = 1.0 - t;
    // S(γ) = s y_i + t y_{i+1} + [(s³ − s) M_i + (t³ − t) M_{i+1}] / 6.
    let mut w = [0.0; 5];
    w[seg] += s;
    w[seg + 1] += t;
    for j in 0..5 {
        w[j] += ((s * s * s - s) * c[seg][j] + (t * t * t - t) * c[seg + 1][j]) / 6.0;
    }
    w
}

/// The exact visible-normal sampler chosen at construction.
#[derive(Clone, Copy, Debug, PartialEq)]
enum VisibleSampler {
    /// `γ = 2` or `α = 1`: GGX itself.
    Ggx,
    /// `γ < 2`: the continuous GGX mixture.
    GgxMixture(MixtureEnvelope),
    /// `γ > 2`: rejection from `GGX(alpha)` with `D <= bound · D_GGX`.
    GgxRejection { alpha: f64, bound: f64 },
}

impl VisibleSampler {
    fn new(gtr: &Gtr) -> Self {
        if gtr.gamma == 2.0 || gtr.alpha == 1.0 {
            VisibleSampler::Ggx
        } else if gtr.gamma < 2.0 {
            VisibleSampler::GgxMixture(MixtureEnvelope::new(gtr.alpha, gtr.gamma))
        } else {
            let (alpha, bound) = best_ggx_proposal(gtr);
            VisibleSampler::GgxRejection { alpha, bound }
        }
    }
}

/// `K(α') = max_m D_γ(m) / D_GGX,α'(m)` and the `α'` (golden-section search in `ln α'`) that
/// minimises it. In `x = cos²θ` the log-ratio `γ ln(1 − kx)^{-1} + 2 ln(1 − k'x)` has one
/// stationary point, `x* = (γk − 2k') / (k k' (γ − 2))`, so the maximum is at 0, 1 or `x*`.
fn best_ggx_proposal(gtr: &Gtr) -> (f64, f64) {
    let bound = |alpha_p: f64| -> f64 {
        let kp = 1.0 - alpha_p * alpha_p;
        let ratio = |x: f64| gtr.d_of_cos2(x) / (alpha_p * alpha_p / (PI * (1.0 - kp * x).powi(2)));
        let mut best = ratio(0.0).max(ratio(1.0));
        let denom = gtr.k * kp * (gtr.gamma - 2.0);
        if denom != 0.0 {
            let x = (gtr.gamma * gtr.k - 2.0 * kp) / denom;
            if x > 0.0 && x < 1.0 {
                best = best.max(ratio(x));
            }
        }
        // Rounding margin: the acceptance test must never see a ratio above the bound.
        best * (1.0 + 1e-9)
    };
    let (mut lo, mut hi) = ((gtr.alpha / 8.0).ln(), (gtr.alpha * 2.0).ln());
    let golden = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..80 {
        let m1 = hi - golden * (hi - lo);
        let m2 = lo + golden * (hi - lo);
        if bound(m1.exp()) < bound(m2.exp()) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    let alpha_p = (0.5 * (lo + hi)).exp();
    (alpha_p, bound(alpha_p))
}

/// The integral of `coef · t^exp` over `[lo, hi]` (`lo = 0` needs `exp > −1`, `hi = ∞` needs
/// `exp < −1`).
fn power_mass(lo: f64, hi: f64, coef: f64, exp: f64) -> f64 {
    let q = exp + 1.0;
    if hi <= lo {
        0.0
    } else if lo == 0.0 {
        coef * hi.powf(q) / q
    } else if hi.is_infinite() {
        -coef * lo.powf(q) / q
    } else {
        let l = (hi / lo).ln();
        coef * lo.powf(q) * l * relative_expm1(q * l)
    }
}

/// The inverse CDF of `t^exp` on `[lo, hi]` at `u`.
fn power_sample(lo: f64, hi: f64, exp: f64, u: f64) -> f64 {
    let q = exp + 1.0;
    if lo == 0.0 {
        hi * u.powf(1.0 / q)
    } else if hi.is_infinite() {
        lo * (1.0 - u).powf(1.0 / q)
    } else {
        let l = (hi / lo).ln();
        // t = lo exp(ln(1 + u expm1(q l)) / q), whose q -> 0 limit is lo e^{u l}.
        let y = if q.abs() < 1e-12 { u * l } else { (u * (q * l).exp_m1()).ln_1p() / q };
        (lo * y.exp()).clamp(lo, hi)
    }
}

/// Envelopes of the unnormalised mixing density `w(t) = t^{1−γ} / ((1 + t)(α² + t))` of the
/// GGX roughness `β_t² = (α² + t)/(1 + t)` (`γ < 2`), times bounds of `β_t` and `β_t²`:
/// `env_j(t) = t^{1−γ} / (max(1, t) max(α², t)) · b_j(t)` with `b_0 = 1`,
/// `b_1 = sqrt(2 max(α², t)/max(1, t)) >= β_t`, `b_2 = b_1² >= β_t²`. Each is a power law on
/// the three pieces cut at `min(1, α²)` and `max(1, α²)`, and `w <= env_0 <= 4 w`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct MixtureEnvelope {
    alpha2: f64,
    gamma: f64,
    /// `∫ env_j` over piece `i`: `mass[j][i]`.
    mass: [[f64; 3]; 3],
}

impl MixtureEnvelope {
    fn new(alpha: f64, gamma: f64) -> Self {
        let mut env = MixtureEnvelope { alpha2: alpha * alpha, gamma, mass: [[0.0; 3]; 3] };
        for j in 0..3 {
            for i in 0..3 {
                let (lo, hi, coef, exp) = env.piece(j, i);
                env.mass[j][i] = power_mass(lo, hi, coef, exp);
            }
        }
        env
    }

    /// `(lo, hi, coef, exp)` of envelope `j` on piece `i`.
    fn piece(&self, j: usize, i: usize) -> (f64, f64, f64, f64) {
        let (a2, g) = (self.alpha2, self.gamma);
        let (t1, t2) = (a2.min(1.0), a2.max(1.0));
        let sq2 = std::f64::consts::SQRT_2;
        // On [t1, t2]: α² < 1 has max(1,t) = 1, max(α²,t) = t; α² > 1 has t and α².
        let below_one = a2 < 1.0;
        match (j, i) {
            (0, 0) => (0.0, t1, 1.0 / a2, 1.0 - g),
            (0, 1) if below_one => (t1, t2, 1.0, -g),
            (0, 1) => (t1, t2, 1.0 / a2, -g),
            (1, 0) => (0.0, t1, sq2 / a2.sqrt(), 1.0 - g),
            (1, 1) if below_one => (t1, t2, sq2, 0.5 - g),
            (1, 1) => (t1, t2, sq2 / a2.sqrt(), -0.5 - g),
            (2, 0) => (0.0, t1, 2.0, 1.0 - g),
            (2, 1) if below_one => (t1, t2, 2.0, 1.0 - g),
            (2, 1) => (t1, t2, 2.0, -1.0 - g),
            (0, _) => (t2, f64::INFINITY, 1.0, -1.0 - g),
            (1, _) => (t2, f64::INFINITY, sq2, -1.0 - g),
            _ => (t2, f64::INFINITY, 2.0, -1.0 - g),
        }
    }

    fn total(&self, j: usize) -> f64 {
        self.mass[j].iter().sum()
    }

    fn env(&self, j: usize, t: f64) -> f64 {
        let t2 = self.alpha2.max(1.0);
        let i = if t < self.alpha2.min(1.0) { 0 } else if t < t2 { 1 } else { 2 };
        let (_, _, coef, exp) = self.piece(j, i);
        coef * t.powf(exp)
    }

    /// A draw from `env_j` (piece by mass, then inversion).
    fn sample_env(&self, j: usize, u_piece: f64, u: f64) -> f64 {
        let mut target = u_piece * self.total(j);
        let mut i = 0;
        while i < 2 && target >= self.mass[j][i] {
            target -= self.mass[j][i];
            i += 1;
        }
        let (lo, hi, _, exp) = self.piece(j, i);
        power_sample(lo, hi, exp, u)
    }

    /// A GGX visible normal whose roughness `β` is drawn with density `∝ w(t) A_β(wi)`.
    fn sample(&self, wi: DVec3, u: [f64; 3]) -> Option<DVec3> {
        let s = (wi.x * wi.x + wi.y * wi.y).sqrt();
        let area = |beta2: f64| area_from_excess(wi, |mu| ggx_excess(beta2, mu));
        // Envelope c_0 env_0 + c_j env_j with A_β(wi) <= c_0 + c_j b_j(t): the flat bound
        // A_β <= A_max, or (above) sqrt(z² + β²s²) <= z + βs, or (below)
        // A_β = β²s²/(2(R + |z|)) <= βs/2 and <= β²s²/(4|z|); the one with the least mass
        // (fewest expected tries) is used.
        let flat = (area(self.alpha2.max(1.0)), 0, 0.0);
        let candidates = if wi.z >= 0.0 {
            [flat, (wi.z, 1, 0.5 * s), flat]
        } else {
            [flat, (0.0, 1, 0.5 * s), (0.0, 2, s * s / (4.0 * -wi.z))]
        };
        let mass = |c: &(f64, usize, f64)| c.0 * self.total(0) + c.2 * self.total(c.1);
        let (c0, j, cj) = candidates.into_iter().min_by(|a, b| mass(a).total_cmp(&mass(b)))?;
        let mass0 = c0 * self.total(0);
        let mass_total = mass0 + cj * self.total(j);
        if !(mass_total > 0.0 && mass_total.is_finite()) {
            return None;
        }
        let mut rng = rejection_generator(&u[2..]);
        for _ in 0..MAX_TRIES {
            let from_first = rng.next_f64() * mass_total < mass0;
            let t = self.sample_env(if from_first { 0 } else { j }, rng.next_f64(), rng.next_f64());
            if !(t > 0.0) || t.is_infinite() {
                continue; // measure zero (u exactly 0 or 1)
            }
            let beta2 = 1.0 - (1.0 - self.alpha2) / (1.0 + t);
            let w = t.powf(1.0 - self.gamma) / ((1.0 + t) * (self.alpha2 + t));
            let envelope = c0 * self.env(0, t) + cj * self.env(j, t);
            if rng.next_f64() * envelope < w * area(beta2) {
                let beta = beta2.sqrt();
                return Ggx { alpha_u: beta, alpha_v: beta }.sample_visible(wi, u);
            }
        }
        None
    }
}
