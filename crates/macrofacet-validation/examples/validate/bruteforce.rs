//! A second, brute-force ground truth for the height-field case, independent of `gpis`: along a
//! ray in the xz-plane, the heights of an isotropic squared-exponential height field restricted
//! to the ray's horizontal track form a 1-D GP `h(s)` with the same kernel. It is sampled on a
//! fine grid by a Cholesky factor of the kernel matrix (written here), row by row until the ray
//! `z(s) = z0 − s cot θ` first dips below `h`. The cross-track slope at a point is independent of
//! the heights on the track (`cov(∂_y h(p), h(q)) ∝ (p_y − q_y) = 0`), so it is drawn separately.

use glam::DVec3;
use macrofacet_validation::stats::Pcg32;

/// The track process `h(s_j)`, `s_j = j ds`, with kernel `σ² exp(−Δs²/(2 l²))`.
pub struct Track {
    pub ds: f64,
    pub cot: f64,
    pub sigma: f64,
    pub lengthscale: f64,
    /// Row-packed lower Cholesky factor of `K + ε I`.
    l: Vec<Vec<f64>>,
    pub jitter: f64,
}

/// One ray: the ray's height where it first crosses (`None`: no crossing on the grid) and the
/// surface normal there.
pub struct Hit {
    pub z: f64,
    pub normal: DVec3,
}

impl Track {
    /// A grid covering the track from `z0` down to `z_min` at incidence `theta_deg`.
    pub fn new(theta_deg: f64, z0: f64, z_min: f64, sigma: f64, lengthscale: f64, ds: f64) -> Track {
        let t = theta_deg.to_radians();
        let cot = t.cos() / t.sin();
        let n = ((z0 - z_min) / cot / ds).ceil() as usize + 2;
        let k = |i: usize, j: usize| {
            let d = (i as f64 - j as f64) * ds;
            sigma * sigma * (-0.5 * d * d / (lengthscale * lengthscale)).exp()
        };
        let mut eps = 1e-12;
        loop {
            if let Some(l) = cholesky(n, &k, eps * sigma * sigma) {
                return Track { ds, cot, sigma, lengthscale, l, jitter: eps };
            }
            eps *= 10.0;
        }
    }

    pub fn points(&self) -> usize {
        self.l.len()
    }

    /// Samples one realization conditioned on `h(0) < z0` (by rejection) and returns the first
    /// crossing of the ray from height `z0`.
    pub fn trace(&self, z0: f64, rng: &mut Pcg32) -> Option<Hit> {
        let gauss = |rng: &mut Pcg32| crate::reference::probit(rng.next_f64_open());
        let mut z = Vec::with_capacity(self.l.len());
        let mut h = Vec::with_capacity(self.l.len());
        'restart: loop {
            z.clear();
            h.clear();
            for j in 0..self.l.len() {
                z.push(gauss(rng));
                let row = &self.l[j];
                let hj: f64 = row.iter().zip(&z).map(|(a, b)| a * b).sum();
                h.push(hj);
                let ray = z0 - j as f64 * self.ds * self.cot;
                let f = ray - hj;
                if j == 0 {
                    if f <= 0.0 {
                        continue 'restart;
                    }
                    continue;
                }
                if f <= 0.0 {
                    let f_prev = z0 - (j - 1) as f64 * self.ds * self.cot - h[j - 1];
                    let frac = f_prev / (f_prev - f);
                    let zc = z0 - (j as f64 - 1.0 + frac) * self.ds * self.cot;
                    // Along-track slope at the crossing: derivative of the cubic through
                    // h[j−2..=j+1] (one more sample is drawn; O(ds³)), or of fewer points at the
                    // ends of the grid.
                    let sc = j as f64 - 1.0 + frac; // crossing in grid units
                    if j + 1 < self.l.len() {
                        z.push(gauss(rng));
                        let row = &self.l[j + 1];
                        h.push(row.iter().zip(&z).map(|(a, b)| a * b).sum());
                    }
                    let lo = j.saturating_sub(2);
                    let hi = (j + 1).min(h.len() - 1);
                    let slope_x = lagrange_derivative(&h[lo..=hi], sc - lo as f64) / self.ds;
                    let slope_y = self.sigma / self.lengthscale * gauss(rng);
                    return Some(Hit { z: zc, normal: DVec3::new(-slope_x, -slope_y, 1.0).normalize() });
                }
            }
            return None;
        }
    }
}

/// Lower Cholesky factor of `K + eps I` (rows `0..=i`), or `None` if not positive definite.
fn cholesky(n: usize, k: &impl Fn(usize, usize) -> f64, eps: f64) -> Option<Vec<Vec<f64>>> {
    let mut l: Vec<Vec<f64>> = Vec::with_capacity(n);
    for i in 0..n {
        let mut row = vec![0.0; i + 1];
        for j in 0..=i {
            let mut s = k(i, j) + if i == j { eps } else { 0.0 };
            let other: &[f64] = if j == i { &row } else { &l[j] };
            s -= (0..j).map(|p| row[p] * other[p]).sum::<f64>();
            if i == j {
                if !(s > 0.0) {
                    return None;
                }
                row[j] = s.sqrt();
            } else {
                row[j] = s / l[j][j];
            }
        }
        l.push(row);
    }
    Some(l)
}

/// Derivative at `x` (in grid units, node `k` at `x = k`) of the Lagrange polynomial through
/// `y[0..n]`.
fn lagrange_derivative(y: &[f64], x: f64) -> f64 {
    let n = y.len();
    let mut d = 0.0;
    for i in 0..n {
        // d/dx Π_{k≠i} (x − k)/(i − k)
        let mut denom = 1.0;
        for k in 0..n {
            if k != i {
                denom *= i as f64 - k as f64;
            }
        }
        let mut sum = 0.0;
        for m in 0..n {
            if m == i {
                continue;
            }
            let mut prod = 1.0;
            for k in 0..n {
                if k != i && k != m {
                    prod *= x - k as f64;
                }
            }
            sum += prod;
        }
        d += y[i] * sum / denom;
    }
    d
}
