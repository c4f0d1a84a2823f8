//! Exact visible-normal sampling of GTR (notes of [`super`]): the continuous GGX mixture for
//! γ < 2, rejection from the best GGX for γ > 2, and the numerical inversion of the vNDF in
//! `(cos θ_m, φ)` that takes over where rejection would be slow.

use super::lambda::{area_from_excess, ggx_excess, relative_expm1};
use super::{Gtr, GL8};
use crate::ndf::ggx::Ggx;
use crate::ndf::MicrofacetDistribution;
use crate::rng::Pcg32;
use glam::DVec3;
use std::f64::consts::PI;

/// Rejection tries before a visible-normal sample falls back to [`Gtr::sample_by_inversion`].
/// Every accepted try is an exact sample whatever its index, so the fallback keeps the output
/// exact; it matters where the acceptance collapses (light tails, γ > 2, seen from below, where
/// a GGX proposal has ~1e-8 of its visible mass where GTR has its own).
const MAX_TRIES: u32 = 48;

/// The exact visible-normal sampler chosen at construction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum VisibleSampler {
    /// `γ = 2` or `α = 1`: GGX itself.
    Ggx,
    /// `γ < 2`: the continuous GGX mixture.
    GgxMixture(MixtureEnvelope),
    /// `γ > 2`: rejection from `GGX(alpha)` with `D <= bound · D_GGX`.
    GgxRejection { alpha: f64, bound: f64 },
}

impl VisibleSampler {
    pub(super) fn new(gtr: &Gtr) -> Self {
        if gtr.gamma == 2.0 || gtr.alpha == 1.0 {
            VisibleSampler::Ggx
        } else if gtr.gamma < 2.0 {
            VisibleSampler::GgxMixture(MixtureEnvelope::new(gtr.alpha, gtr.gamma))
        } else {
            let (alpha, bound) = best_ggx_proposal(gtr);
            VisibleSampler::GgxRejection { alpha, bound }
        }
    }

    /// A visible normal from `wi` (`None` only when nothing is visible).
    pub(super) fn sample(&self, gtr: &Gtr, wi: DVec3, u: [f64; 3]) -> Option<DVec3> {
        match *self {
            VisibleSampler::Ggx => Ggx { alpha_u: gtr.alpha, alpha_v: gtr.alpha }.sample_visible(wi, u),
            VisibleSampler::GgxMixture(env) => env.sample(wi, u).or_else(|| gtr.sample_by_inversion(wi, u)),
            VisibleSampler::GgxRejection { alpha, bound } => {
                // Expected tries = K A_GGX(wi) / A(wi): where they exceed 32 (light tails seen
                // from below or at grazing angles) the inversion is cheaper.
                let proposal_area = Ggx { alpha_u: alpha, alpha_v: alpha }.projected_area(wi);
                if bound * proposal_area > 32.0 * gtr.exact_projected_area(wi) {
                    gtr.sample_by_inversion(wi, u)
                } else {
                    gtr.sample_by_rejection(alpha, bound, wi, u).or_else(|| gtr.sample_by_inversion(wi, u))
                }
            }
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
    Pcg32::new(h, 0x0067_7472) // "gtr"
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
pub(super) struct MixtureEnvelope {
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
