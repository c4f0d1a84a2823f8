//! Reference formulas written independently of the library's maths (they use `libm`, `glam` and,
//! for the samplers' random numbers only, the library's seeded generator `stats::Pcg32`):
//! Gauss–Legendre quadrature, the normal cdf and its inverse, conductor Fresnel from complex
//! arithmetic, Beckmann and GGX `D`, Smith `Λ` and visible-normal samplers, the analytic
//! single-scattering microfacet albedo (height-correlated Smith, by quadrature), the Heitz,
//! Hanika, d'Eon and Dachsbacher 2016 microsurface random walk (with Gaussian heights) and its
//! next-event estimate of the BRDF, and Chandrasekhar's H-function (seeds/002 Eq. 31).

use glam::DVec3;
use crate::stats::Pcg32;
use std::f64::consts::{PI, SQRT_2};

/// `(P_n(x), P_{n-1}(x))` by the three-term Legendre recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    for k in 2..=n {
        let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
        p0 = p1;
        p1 = p2;
    }
    (p1, p0)
}

/// Gauss–Legendre nodes and weights on [-1, 1] (Newton on the Legendre recurrence).
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let derivative = |x: f64| {
        let (p1, p0) = legendre(n, x);
        (p1, n as f64 * (x * p1 - p0) / (x * x - 1.0))
    };
    (0..n)
        .map(|i| {
            let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            for _ in 0..100 {
                let (p, dp) = derivative(x);
                let dx = p / dp;
                x -= dx;
                if dx.abs() < 1e-15 {
                    break;
                }
            }
            let dp = derivative(x).1;
            (x, 2.0 / ((1.0 - x * x) * dp * dp))
        })
        .collect()
}

/// `∫_a^b f` by `panels` panels of an `n`-point Gauss–Legendre rule.
pub fn integrate(f: impl Fn(f64) -> f64, a: f64, b: f64, panels: usize, gl: &[(f64, f64)]) -> f64 {
    let h = (b - a) / panels as f64;
    let mut s = 0.0;
    for p in 0..panels {
        let (lo, hi) = (a + p as f64 * h, a + (p + 1) as f64 * h);
        for &(x, w) in gl {
            s += 0.5 * h * w * f(0.5 * (lo + hi) + 0.5 * (hi - lo) * x);
        }
    }
    s
}

pub fn normal_cdf(x: f64) -> f64 {
    0.5 * libm::erfc(-x / SQRT_2)
}

/// Inverse of [`normal_cdf`]: Acklam's rational approximation polished by two Halley steps.
pub fn probit(p: f64) -> f64 {
    if !(p > 0.0) {
        return f64::NEG_INFINITY;
    }
    if !(p < 1.0) {
        return f64::INFINITY;
    }
    const A: [f64; 6] = [-3.969683028665376e1, 2.209460984245205e2, -2.759285104469687e2, 1.383577518672690e2, -3.066479806614716e1, 2.506628277459239];
    const B: [f64; 5] = [-5.447609879822406e1, 1.615858368580409e2, -1.556989798598866e2, 6.680131188771972e1, -1.328068155288572e1];
    const C: [f64; 6] = [-7.784894002430293e-3, -3.223964580411365e-1, -2.400758277161838, -2.549732539343734, 4.374664141464968, 2.938163982698783];
    const D: [f64; 4] = [7.784695709041462e-3, 3.224671290700398e-1, 2.445134137142996, 3.754408661907416];
    let q_low = 0.02425;
    let mut x = if p < q_low {
        let q = (-2.0 * p.ln()).sqrt();
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5]) / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    } else if p <= 1.0 - q_low {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    } else {
        let q = (-2.0 * (1.0 - p).ln()).sqrt();
        -(((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5]) / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    for _ in 0..2 {
        // Halley on Φ(x) − p, with the tail-accurate difference for p > 1/2.
        let e = if p > 0.5 { (1.0 - p) - 0.5 * libm::erfc(x / SQRT_2) } else { normal_cdf(x) - p };
        let u = e * (2.0 * PI).sqrt() * (0.5 * x * x).exp();
        x -= u / (1.0 + 0.5 * x * u);
    }
    x
}

// ---------------------------------------------------------------------------------------------
// Conductor Fresnel with complex arithmetic
// ---------------------------------------------------------------------------------------------

#[derive(Clone, Copy, Debug)]
struct Cx(f64, f64);
impl Cx {
    fn add(self, o: Cx) -> Cx {
        Cx(self.0 + o.0, self.1 + o.1)
    }
    fn sub(self, o: Cx) -> Cx {
        Cx(self.0 - o.0, self.1 - o.1)
    }
    fn mul(self, o: Cx) -> Cx {
        Cx(self.0 * o.0 - self.1 * o.1, self.0 * o.1 + self.1 * o.0)
    }
    fn div(self, o: Cx) -> Cx {
        let d = o.0 * o.0 + o.1 * o.1;
        Cx((self.0 * o.0 + self.1 * o.1) / d, (self.1 * o.0 - self.0 * o.1) / d)
    }
    fn norm2(self) -> f64 {
        self.0 * self.0 + self.1 * self.1
    }
    fn sqrt(self) -> Cx {
        let r = self.norm2().sqrt();
        let re = (0.5 * (r + self.0)).max(0.0).sqrt();
        let im = (0.5 * (r - self.0)).max(0.0).sqrt();
        Cx(re, if self.1 < 0.0 { -im } else { im })
    }
}

/// Unpolarised reflectance of a conductor of complex index `eta + i k` from Snell's law and
/// the Fresnel amplitude coefficients evaluated in complex arithmetic.
pub fn fresnel(cos_i: f64, eta: f64, k: f64) -> f64 {
    let c = cos_i.clamp(0.0, 1.0);
    let n = Cx(eta, k);
    let s2 = Cx(1.0 - c * c, 0.0);
    let cos_t = Cx(1.0, 0.0).sub(s2.div(n.mul(n))).sqrt();
    let ci = Cx(c, 0.0);
    let rs = ci.sub(n.mul(cos_t)).div(ci.add(n.mul(cos_t)));
    let rp = n.mul(ci).sub(cos_t).div(n.mul(ci).add(cos_t));
    0.5 * (rs.norm2() + rp.norm2())
}

pub fn fresnel_rgb(cos_i: f64, eta: [f64; 3], k: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|c| fresnel(cos_i, eta[c], k[c]))
}

// ---------------------------------------------------------------------------------------------
// Isotropic Beckmann and GGX: D, Λ, visible normals
// ---------------------------------------------------------------------------------------------

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Dist {
    Beckmann(f64),
    Ggx(f64),
}

impl Dist {
    pub fn alpha(&self) -> f64 {
        match *self {
            Dist::Beckmann(a) | Dist::Ggx(a) => a,
        }
    }

    pub fn name(&self) -> &'static str {
        match self {
            Dist::Beckmann(_) => "Beckmann",
            Dist::Ggx(_) => "GGX",
        }
    }

    /// `D(m)` for `m.z > 0`, zero below.
    pub fn d(&self, m: DVec3) -> f64 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let a = self.alpha();
        let c2 = m.z * m.z;
        let t2 = (1.0 - c2).max(0.0) / c2;
        match self {
            Dist::Beckmann(_) => (-t2 / (a * a)).exp() / (PI * a * a * c2 * c2),
            Dist::Ggx(_) => {
                let q = 1.0 + t2 / (a * a);
                1.0 / (PI * a * a * c2 * c2 * q * q)
            }
        }
    }

    /// Smith's `Λ(w)`, extended below the horizon by `Λ(w) = −1 − Λ(−w)`.
    pub fn lambda(&self, w: DVec3) -> f64 {
        if w.z < 0.0 {
            return -1.0 - self.lambda(-w);
        }
        let s2 = (w.x * w.x + w.y * w.y).max(0.0);
        if s2 == 0.0 {
            return 0.0;
        }
        if w.z == 0.0 {
            return f64::INFINITY;
        }
        let tan = s2.sqrt() / w.z;
        let a = self.alpha();
        match self {
            Dist::Beckmann(_) => {
                let nu = 1.0 / (a * tan);
                0.5 * (libm::erf(nu) - 1.0) + (-nu * nu).exp() / (2.0 * nu * PI.sqrt())
            }
            Dist::Ggx(_) => 0.5 * (-1.0 + (1.0 + a * a * tan * tan).sqrt()),
        }
    }

    /// `∫ <w, m> D(m) dm = (1 + Λ(w)) w.z` (valid on the whole sphere with the extended Λ).
    /// For `w.z < 0` it is written `Λ(−w) |w.z|`, which does not cancel.
    pub fn projected_area(&self, w: DVec3) -> f64 {
        if w.z < 0.0 {
            self.lambda(-w) * -w.z
        } else {
            (1.0 + self.lambda(w)) * w.z
        }
    }

    /// A normal from `D_wi(m) ∝ <wi, m> D(m)`; `wi` anywhere on the sphere.
    pub fn sample_vndf(&self, wi: DVec3, rng: &mut Pcg32) -> Option<DVec3> {
        match *self {
            Dist::Beckmann(a) => beckmann_vndf(a, wi, rng),
            Dist::Ggx(a) => Some(ggx_vndf(a, wi, rng.next_f64(), rng.next_f64())),
        }
    }
}

/// Beckmann visible normals by visible slopes (Heitz & d'Eon 2014, Sec. 4): in the stretched
/// configuration with `wi` at polar angle θ the slope `x̃` has density `∝ (cot θ − x̃)₊ e^{−x̃²}`
/// and `ỹ ~ N(0, ½)`. `x̃` is drawn by safeguarded Newton on its cdf for `cot θ ≥ −1` and, below
/// (where the cdf cancels), by rejection from a Gamma(2) proposal for `cot θ − x̃`.
fn beckmann_vndf(alpha: f64, wi: DVec3, rng: &mut Pcg32) -> Option<DVec3> {
    let ws = DVec3::new(alpha * wi.x, alpha * wi.y, wi.z).normalize();
    let sin = (ws.x * ws.x + ws.y * ws.y).sqrt();
    let gauss = |rng: &mut Pcg32| probit(rng.next_f64_open()) / SQRT_2;
    let (xs, ys) = if sin < 1e-9 {
        if ws.z < 0.0 {
            return None;
        }
        (gauss(rng), gauss(rng))
    } else {
        let c = ws.z / sin;
        let x = sample_visible_slope(c, rng);
        let y = gauss(rng);
        let (cp, sp) = (ws.x / sin, ws.y / sin);
        (cp * x - sp * y, sp * x + cp * y)
    };
    Some(DVec3::new(-alpha * xs, -alpha * ys, 1.0).normalize())
}

/// `x` with density `∝ (c − x)₊ e^{−x²}`.
fn sample_visible_slope(c: f64, rng: &mut Pcg32) -> f64 {
    let sqrt_pi = PI.sqrt();
    if c >= -1.0 {
        // G(x) = ∫_{−∞}^x (c − t) e^{−t²} dt = c (√π/2) erfc(−x) + e^{−x²}/2, x ≤ c.
        let g = |x: f64| c * 0.5 * sqrt_pi * libm::erfc(-x) + 0.5 * (-x * x).exp();
        let target = rng.next_f64_open() * g(c);
        let (mut lo, mut hi) = ((-10.0f64).min(c - 10.0), c);
        let mut x = (c - 1.0).max(-2.0).min(c);
        for _ in 0..100 {
            let r = g(x) - target;
            if r > 0.0 {
                hi = x;
            } else {
                lo = x;
            }
            let slope = (c - x) * (-x * x).exp();
            let newton = x - r / slope;
            let next = if slope > 0.0 && newton > lo && newton < hi { newton } else { 0.5 * (lo + hi) };
            if (next - x).abs() < 1e-13 * (1.0 + x.abs()) || hi - lo < 1e-14 {
                return next;
            }
            x = next;
        }
        x
    } else {
        // y = c − x > 0 with density ∝ y e^{−(y + |c|)²} ∝ y e^{−2|c| y} · e^{−y²}.
        let b = -c;
        loop {
            let y = -(rng.next_f64_open().ln() + rng.next_f64_open().ln()) / (2.0 * b); // Gamma(2, 2b)
            if rng.next_f64() < (-y * y).exp() {
                return c - y;
            }
        }
    }
}

/// Heitz 2018, "Sampling the GGX distribution of visible normals", Listing 1 (isotropic).
fn ggx_vndf(alpha: f64, v: DVec3, u1: f64, u2: f64) -> DVec3 {
    let vh = DVec3::new(alpha * v.x, alpha * v.y, v.z).normalize();
    let lensq = vh.x * vh.x + vh.y * vh.y;
    let t1 = if lensq > 0.0 { DVec3::new(-vh.y, vh.x, 0.0) / lensq.sqrt() } else { DVec3::X };
    let t2 = vh.cross(t1);
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    DVec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0)).normalize()
}

// ---------------------------------------------------------------------------------------------
// Analytic single scattering
// ---------------------------------------------------------------------------------------------

/// `f₁(wi, wo) cos θo = F(wi·h) D(h) G₂(wi, wo) / (4 cos θi)` with the height-correlated
/// `G₂ = 1/(1 + Λ(wi) + Λ(wo))` (seeds/002 §3; Heitz 2014).
pub fn single_scattering_density(dist: &Dist, eta: [f64; 3], k: [f64; 3], wi: DVec3, wo: DVec3) -> [f64; 3] {
    if wi.z <= 0.0 || wo.z <= 0.0 {
        return [0.0; 3];
    }
    let h = (wi + wo).normalize();
    let g2 = 1.0 / (1.0 + dist.lambda(wi) + dist.lambda(wo));
    let f = fresnel_rgb(wi.dot(h), eta, k);
    f.map(|x| x * dist.d(h) * g2 / (4.0 * wi.z))
}

/// Directional albedo of [`single_scattering_density`], `∫ f₁ cos θo dωo`, by quadrature over
/// the half vector in slope space: `dωo = 4 (wi·m) dm`, `D(m) dm = P₂₂(s) d²s / m_z`, the radial
/// slope variable mapped through its cdf (`u = 1 − v²`, which removes the GGX tail's
/// `(1 − u)^{−1/2}`), `panels × 8` Gauss–Legendre nodes in `v` and in `φ ∈ [0, π]` (the
/// integrand is even in φ for `wi` in the xz-plane).
pub fn single_scattering_albedo(dist: &Dist, eta: [f64; 3], k: [f64; 3], theta_i: f64, panels: usize) -> [f64; 3] {
    let wi = DVec3::new(theta_i.sin(), 0.0, theta_i.cos());
    let gl = gauss_legendre(8);
    let a = dist.alpha();
    let mut total = [0.0; 3];
    let hv = 1.0 / panels as f64;
    let hp = PI / panels as f64;
    for pv in 0..panels {
        for &(xv, wv) in &gl {
            let v = (pv as f64 + 0.5 + 0.5 * xv) * hv;
            let w_v = 0.5 * hv * wv * 2.0 * v; // du = 2 v dv
            let u = 1.0 - v * v;
            let r = match dist {
                Dist::Beckmann(_) => a * (-2.0 * v.ln()).sqrt(), // −ln(1 − u) = −2 ln v
                Dist::Ggx(_) => a * (u / (v * v)).sqrt(),
            };
            for pp in 0..panels {
                for &(xp, wp) in &gl {
                    let phi = (pp as f64 + 0.5 + 0.5 * xp) * hp;
                    let w_phi = 0.5 * hp * wp / PI; // ∫_0^π dφ/π = mean over the full circle
                    let m = DVec3::new(-r * phi.cos(), -r * phi.sin(), 1.0).normalize();
                    let cos_im = wi.dot(m);
                    if cos_im <= 0.0 {
                        continue;
                    }
                    let wo = 2.0 * cos_im * m - wi;
                    if wo.z <= 0.0 {
                        continue;
                    }
                    let g2 = 1.0 / (1.0 + dist.lambda(wi) + dist.lambda(wo));
                    let f = fresnel_rgb(cos_im, eta, k);
                    let common = w_v * w_phi * cos_im / m.z * g2 / wi.z;
                    for c in 0..3 {
                        total[c] += common * f[c];
                    }
                }
            }
        }
    }
    total
}

// ---------------------------------------------------------------------------------------------
// The Heitz et al. 2016 microsurface random walk (Gaussian heights, C1 = Φ)
// ---------------------------------------------------------------------------------------------

/// Heitz 2016 `sampleHeight`: the height of the next intersection of the ray leaving height `hr`
/// along `wr`, or `None` when it escapes.
fn sample_height(dist: &Dist, wr: DVec3, hr: f64, u: f64) -> Option<f64> {
    if wr.z > 0.9999 {
        return None;
    }
    if wr.z < -0.9999 {
        return Some(probit(u * normal_cdf(hr)));
    }
    if wr.z.abs() < 1e-4 {
        return Some(hr);
    }
    let lambda = dist.lambda(wr);
    let c1 = normal_cdf(hr);
    if wr.z > 0.0 {
        let g1 = c1.powf(lambda);
        if u > 1.0 - g1 {
            return None;
        }
    }
    Some(probit(c1 / (1.0 - u).powf(1.0 / lambda)))
}

/// The outcome of one walk: throughput per channel and number of reflections.
pub struct HeitzPath {
    pub energy: [f64; 3],
    pub order: u32,
}

/// One path entering from `wi` (toward the light): reflect about visible normals with conductor
/// Fresnel until the ray escapes (`max_order` caps it, counted as absorbed).
pub fn heitz_walk(dist: &Dist, eta: [f64; 3], k: [f64; 3], wi: DVec3, max_order: u32, rng: &mut Pcg32) -> HeitzPath {
    let mut wr = -wi;
    let mut hr = f64::INFINITY;
    let mut energy = [1.0; 3];
    for order in 0..max_order {
        match sample_height(dist, wr, hr, rng.next_f64()) {
            None => return HeitzPath { energy, order },
            Some(h) => hr = h,
        }
        let Some(m) = dist.sample_vndf(-wr, rng) else { return HeitzPath { energy: [0.0; 3], order } };
        let f = fresnel_rgb((-wr).dot(m), eta, k);
        energy = [0, 1, 2].map(|c| energy[c] * f[c]);
        wr = (wr - 2.0 * wr.dot(m) * m).normalize();
    }
    HeitzPath { energy: [0.0; 3], order: max_order }
}

/// The microflake phase function of the microsurface seen as a volume (Heitz 2016 Sec. 5.2):
/// `p(wi, wo) = F(wi·h) D(h) / (4 σ(wi))`, `σ(wi) = (1 + Λ(wi)) wi.z`, with `wi` pointing away.
fn heitz_phase(dist: &Dist, eta: [f64; 3], k: [f64; 3], wi: DVec3, wo: DVec3) -> [f64; 3] {
    let Some(h) = (wi + wo).try_normalize() else { return [0.0; 3] };
    if h.z <= 0.0 {
        return [0.0; 3];
    }
    let area = dist.projected_area(wi);
    if !(area > 0.0) {
        return [0.0; 3];
    }
    let f = fresnel_rgb(wi.dot(h), eta, k);
    f.map(|x| x * dist.d(h) / (4.0 * area))
}

/// Next-event estimate of `f_r(wi, wo) cos θo` for every `wo` of `wos` from one walk: at every
/// intersection (height `h`, arriving along `wr`) adds `energy · p(−wr, wo) · Φ(h)^{Λ(wo)}`.
/// Returns the all-orders and the single-scattering contributions.
pub fn heitz_nee(dist: &Dist, eta: [f64; 3], k: [f64; 3], wi: DVec3, wos: &[DVec3], rng: &mut Pcg32, all: &mut [[f64; 3]], single: &mut [[f64; 3]]) {
    let mut wr = -wi;
    let mut hr = f64::INFINITY;
    let mut energy = [1.0; 3];
    for order in 0..1000 {
        match sample_height(dist, wr, hr, rng.next_f64()) {
            None => return,
            Some(h) => hr = h,
        }
        for (j, wo) in wos.iter().enumerate() {
            let p = heitz_phase(dist, eta, k, -wr, *wo);
            let g1 = normal_cdf(hr).powf(dist.lambda(*wo));
            for c in 0..3 {
                let v = energy[c] * p[c] * g1;
                all[j][c] += v;
                if order == 0 {
                    single[j][c] += v;
                }
            }
        }
        let Some(m) = dist.sample_vndf(-wr, rng) else { return };
        let f = fresnel_rgb((-wr).dot(m), eta, k);
        energy = [0, 1, 2].map(|c| energy[c] * f[c]);
        wr = (wr - 2.0 * wr.dot(m) * m).normalize();
    }
}

// ---------------------------------------------------------------------------------------------
// Chandrasekhar
// ---------------------------------------------------------------------------------------------

/// Chandrasekhar's H-function for isotropic scattering with single-scattering albedo `a < 1`,
/// seeds/002 Eq. 31: `H(μ) = exp(−(μ/π) ∫_0^{π/2} ln(1 − a t cot t) / (cos² t + μ² sin² t) dt)`
/// (32 panels of 16-point Gauss–Legendre; the integrand is smooth for `a < 1`).
pub fn h_function(mu: f64, a: f64) -> f64 {
    let gl = gauss_legendre(16);
    let integrand = |t: f64| {
        // 1 - a t cot t = (1 - a) + a (1 - t cot t), the latter by its series for small t
        // (t cot t rounds to 1 there).
        let t2 = t * t;
        let one_minus_t_cot = if t < 1e-2 { t2 / 3.0 + t2 * t2 / 45.0 + 2.0 * t2 * t2 * t2 / 945.0 } else { 1.0 - t / t.tan() };
        let (s, c) = t.sin_cos();
        ((1.0 - a) + a * one_minus_t_cot).ln() / (c * c + mu * mu * s * s)
    };
    // Panels halving toward t = 0, where a = 1 gives a logarithmic singularity (1 - t cot t ~ t²/3);
    // what is left below 2^-40 π/2 contributes below 1e-10.
    (0..40)
        .map(|k| {
            let hi = 0.5 * PI * 0.5f64.powi(k);
            integrate(integrand, 0.5 * hi, hi, 1, &gl)
        })
        .sum::<f64>()
        .mul_add(-mu / PI, 0.0)
        .exp()
}
