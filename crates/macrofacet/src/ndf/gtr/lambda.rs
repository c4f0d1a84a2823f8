//! Smith's Λ of GTR: the exact projected area of `D` as a Gauss–Jacobi mixture of closed forms
//! (GGX below γ = 2, GTR_4 above; see the notes of [`super`]) and Dimov's closed forms with their
//! spline in γ (seeds/001 Eqs. 34–39). Both are written as the "excess" `e(μ) = μ Λ(μ)` at
//! `μ = cot θ`, finite at the horizon.

use super::gauss_jacobi::gauss_jacobi;
use glam::DVec3;

/// Gauss–Jacobi nodes of the exact projected-area mixture (see the module notes).
const MIXTURE_NODES: usize = 20;

/// The projected area `∫ <w, m> D dm` of an isotropic height-field NDF from its excess
/// `e(μ) = μ Λ(μ)`, for any (not necessarily unit) `w` — the area is homogeneous of degree 1:
/// with `s = |w_t|`, `s e(w_z/s) + w_z` above and `s e(−w_z/s)` below (seeds/001 Eq. 39 gives the signed
/// identity `A(w) − A(−w) = w_z`).
pub(super) fn area_from_excess(w: DVec3, excess: impl Fn(f64) -> f64) -> f64 {
    let s = (w.x * w.x + w.y * w.y).sqrt();
    if s == 0.0 {
        return w.z.max(0.0);
    }
    let mu = w.z.abs() / s;
    // Far above the pole the excess is below one ulp of w_z (s e ~ s² β²/(4 w_z), below 1e-188
    // for μ > 1e100 and every admitted roughness): skip it, before the closed forms' μ³
    // overflows (GTR_4 near the normal gave NaN, found by fuzzing).
    let e = if mu > 1e100 { 0.0 } else { s * excess(mu) };
    if w.z >= 0.0 {
        w.z + e
    } else {
        e
    }
}

/// `e(μ) = (sqrt(β² + μ²) − μ)/2` of GGX, cancellation-free.
pub(super) fn ggx_excess(beta2: f64, mu: f64) -> f64 {
    0.5 * beta2 / ((beta2 + mu * mu).sqrt() + mu)
}

/// `e(μ) = μ/S_4(μ) − μ` of GTR_4 with roughness² `a2` (seeds/001 Eq. 39), with
/// `μ³ − B³ = −a2 (μ² + μB + B²)/(μ + B)` so that nothing cancels for small `a2`, and every
/// term divided by `B³` (with `r = μ/B`) so that nothing overflows: `μ³ a2²` did at μ = 2e97,
/// α = 1e3 (Λ = −∞ near the normal, found by fuzzing).
pub(super) fn gtr4_excess(a2: f64, mu: f64) -> f64 {
    let big_a = 8.0 * (a2 * a2 + a2 + 1.0);
    let b = (mu * mu + a2).sqrt();
    let r = mu / b;
    let head = -a2 * r * (r * r + r + 1.0) / (r + 1.0);
    let tail = 3.0 * a2 / big_a * (a2 * (5.0 * a2 * a2 + 2.0 * a2 + 1.0) / (b * b) + 4.0 * r * r * (2.0 * a2 * a2 + a2 + 1.0));
    (head + tail) / (2.0 * b)
}

/// The exact projected area as a Gauss–Jacobi mixture of closed forms (module notes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct ProjectedAreaMixture {
    /// 2: GGX components (`γ <= 2`); 4: GTR_4 components (`γ > 2`).
    base: u8,
    nodes: usize,
    beta2: [f64; MIXTURE_NODES],
    weight: [f64; MIXTURE_NODES],
}

impl ProjectedAreaMixture {
    pub(super) fn new(alpha: f64, gamma: f64) -> Self {
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

    pub(super) fn excess(&self, mu: f64) -> f64 {
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
/// `ex(x − ln α²)^{n−1−γ} ex(x)^{γ−1}` with `ex(y) = expm1(y)/y` (and `(p² + p + 1)/p²`, `p = β²`,
/// from the normalisation of GTR_4).
pub(super) fn mixture_nodes(alpha: f64, gamma: f64, base: u8, n: usize) -> (Vec<f64>, Vec<f64>) {
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

/// `expm1(y)/y`, 1 at 0.
pub(super) fn relative_expm1(y: f64) -> f64 {
    if y.abs() < 1e-300 {
        1.0
    } else {
        y.exp_m1() / y
    }
}

/// `ln(1 + z)/z`, 1 at 0.
pub(super) fn relative_ln_1p(z: f64) -> f64 {
    if z.abs() < 1e-300 {
        1.0
    } else {
        z.ln_1p() / z
    }
}

/// Dimov's `μ/S_γ(μ) − μ` (seeds/001 Eqs. 35–39 with `G1 = S`, `S = 1/(1 + Λ)`): the five
/// closed forms as `1/F_j = S_j/μ` and the natural cubic spline in `γ` through them (the paper
/// splines `S_γ`; at fixed `μ` that is the same as splining `S/μ`).
pub(super) fn dimov_excess(alpha: f64, ln_alpha2: f64, weights: &[f64; 5], mu: f64) -> f64 {
    let a2 = alpha * alpha;
    let b = (mu * mu + 1.0).sqrt(); // B_1
    let a = (mu * mu + a2).sqrt(); // A_1 = A_3 = B_4
    // Each closed form as its excess e_j = F_j − μ, F_j = μ/S_j, free of cancellation:
    // seeds/001 Eq. 35: F_0 = (μ + sqrt(1 + μ²))/2.
    let e0 = 0.5 / (b + mu);
    // seeds/001 Eq. 36 regrouped in d = α² − 1 = expm1(L), L = ln α²:
    // e_1 = (d/L) / (A + B) · [1 − μ lnratio(z)/(μ + A)], z = −d/((A + B)(μ + A)).
    let d = ln_alpha2.exp_m1();
    let z = -d / ((a + b) * (mu + a));
    let e1 = relative_expm1(ln_alpha2) / (a + b) * (1.0 - mu * relative_ln_1p(z) / (mu + a));
    // seeds/001 Eq. 37 (GGX).
    let e2 = ggx_excess(a2, mu);
    // seeds/001 Eq. 38: F_3 = (α²(3α² + 1) + 2μ B_3 (μ + A_3)) / (4 B_3 A_3), B_3 = α² + 1, so
    // e_3 = α² (3α² + 1 − 2μ B_3/(μ + A_3)) / (4 B_3 A_3).
    let b3 = a2 + 1.0;
    let e3 = a2 * (3.0 * a2 + 1.0 - 2.0 * mu * b3 / (mu + a)) / (4.0 * b3 * a);
    // seeds/001 Eq. 39.
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
pub(super) fn natural_spline_weights(gamma: f64) -> [f64; 5] {
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
