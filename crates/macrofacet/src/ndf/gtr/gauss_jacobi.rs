//! Gauss–Jacobi quadrature by Golub–Welsch: the nodes of the exact projected-area mixture of
//! GTR ([`super::lambda`]), whose mixing density has Beta-type end singularities.

/// Gauss–Jacobi nodes on `(−1, 1)` for the weight `(1 − z)^a (1 + z)^b` and their weights up to
/// a common factor: Golub–Welsch (eigenvalues of the Jacobi matrix of the monic recurrence by
/// implicit QL, weights from the eigenvectors' first components).
pub(super) fn gauss_jacobi(n: usize, a: f64, b: f64) -> (Vec<f64>, Vec<f64>) {
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
