//! Small dense linear algebra for Gaussian conditioning: a Cholesky factorisation with a relative
//! diagonal jitter that grows on failure, triangular solves, and sampling of a (possibly
//! singular) multivariate normal.
//!
//! Squared-exponential Gram matrices are notoriously ill-conditioned (the process is analytic:
//! a few close samples nearly determine the next one). Every factorisation therefore adds a
//! relative *nugget* `ε · A_ii` with `ε = jitter` (default [`super::DEFAULT_JITTER`]); if a pivot
//! is still not positive (or not finite) `ε` is multiplied by 100 and the factorisation retried,
//! up to `ε = 1`, after which a diagonal factor is used. A nugget `ε σ²` is equivalent to
//! observing the previous samples with noise of standard deviation `√ε σ` (3e-5 σ for
//! ε = 1e-9): far below anything a crossing statistic can see, and it keeps every result finite.

/// A lower-triangular factor `L` (row-major, `n × n`) with `L Lᵀ = A + jitter · diag(A)`.
#[derive(Clone, Debug)]
pub struct Cholesky {
    pub n: usize,
    pub l: Vec<f64>,
    /// The relative jitter `ε` that was finally used.
    pub jitter: f64,
}

fn try_factor(a: &[f64], n: usize, nugget: &[f64], l: &mut [f64]) -> bool {
    for i in 0..n {
        for j in 0..=i {
            let mut s = a[i * n + j];
            if i == j {
                s += nugget[i];
            }
            for k in 0..j {
                s -= l[i * n + k] * l[j * n + k];
            }
            if i == j {
                if !(s > 0.0) || !s.is_finite() {
                    return false;
                }
                l[i * n + i] = s.sqrt();
            } else {
                l[i * n + j] = s / l[j * n + j];
            }
        }
    }
    true
}

/// Factors the symmetric `n × n` matrix `a` (row-major; only the lower triangle is read) plus a
/// relative nugget: `A + ε diag(A)` (each observation is jittered in proportion to its own prior
/// variance, so value and derivative rows of very different scales are treated alike; a zero
/// diagonal entry gets `ε · mean(diag)`). `ε` starts at `rel_jitter` and grows ×100 on failure
/// (module documentation). Never panics, never returns NaN for finite input.
pub fn cholesky_jittered(a: &[f64], n: usize, rel_jitter: f64) -> Cholesky {
    let mut l = vec![0.0; n * n];
    let mean_diag = if n == 0 { 0.0 } else { (0..n).map(|i| a[i * n + i].abs()).sum::<f64>() / n as f64 };
    let scale = if mean_diag > 0.0 && mean_diag.is_finite() { mean_diag } else { 1.0 };
    let nugget_of = |i: usize, eps: f64| {
        let d = a[i * n + i];
        eps * if d > 0.0 && d.is_finite() { d } else { scale }
    };
    let mut eps = rel_jitter.max(1e-15);
    while eps <= 1.0 {
        let nugget: Vec<f64> = (0..n).map(|i| nugget_of(i, eps)).collect();
        if try_factor(a, n, &nugget, &mut l) {
            return Cholesky { n, l, jitter: eps };
        }
        eps *= 100.0;
    }
    // Last resort: a diagonal factor (drops all correlation; only reached for garbage input).
    l.iter_mut().for_each(|x| *x = 0.0);
    for i in 0..n {
        let d = a[i * n + i];
        l[i * n + i] = if d > 0.0 && d.is_finite() { (2.0 * d).sqrt() } else { scale.sqrt() };
    }
    Cholesky { n, l, jitter: 1.0 }
}

impl Cholesky {
    /// Solves `L x = b` (forward substitution).
    pub fn forward(&self, b: &[f64]) -> Vec<f64> {
        let n = self.n;
        let mut x = b.to_vec();
        for i in 0..n {
            // (In order: the same rounding as subtracting term by term.)
            let s = self.l[i * n..i * n + i].iter().zip(&x[..i]).fold(x[i], |s, (l, xk)| s - l * xk);
            x[i] = s / self.l[i * n + i];
        }
        x
    }
}

/// Samples `N(mean, cov)` for a small symmetric positive *semi*-definite `cov` (row-major
/// `n × n`): a pivot-tolerant Cholesky where pivots below `1e-13 · max(diag)` are set to zero
/// (deterministic directions), so exactly singular covariances — e.g. the deterministic
/// `∂_z f` of a height field — are handled without jitter. `normal` supplies standard normals.
pub fn sample_psd(mean: &[f64], cov: &[f64], n: usize, normal: &mut impl FnMut() -> f64) -> Vec<f64> {
    let max_diag = (0..n).map(|i| cov[i * n + i]).fold(0.0f64, f64::max);
    let tol = 1e-13 * max_diag;
    let mut l = vec![0.0; n * n];
    for j in 0..n {
        let mut d = cov[j * n + j];
        for k in 0..j {
            d -= l[j * n + k] * l[j * n + k];
        }
        if !(d > tol) || !d.is_finite() {
            continue; // column stays zero
        }
        let ljj = d.sqrt();
        l[j * n + j] = ljj;
        for i in j + 1..n {
            let mut s = cov[i * n + j];
            for k in 0..j {
                s -= l[i * n + k] * l[j * n + k];
            }
            l[i * n + j] = s / ljj;
        }
    }
    let z: Vec<f64> = (0..n).map(|_| normal()).collect();
    (0..n).map(|i| mean[i] + (0..=i).map(|k| l[i * n + k] * z[k]).sum::<f64>()).collect()
}
