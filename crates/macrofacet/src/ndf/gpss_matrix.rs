//! The generalized macrofacet with a full local anisotropy: the kernel of a non-stationary GPSS
//! (seeds/004 Eqs. 25–26) is locally `σ² k(sqrt(Δᵀ Σ⁻¹ Δ))`, so the gradient at a crossing is
//! `g ~ N(e_z, Q/2)` with the "α² matrix" `Q = 2 σ² Σ⁻¹` written in the local frame (a
//! frame-aligned `Σ = diag(l²)` gives `Q = diag(α²)`, seeds/000 Eq. 4). `Q` couples the normal
//! and the tangents when `Σ`'s axes are not those of the mean surface.
//!
//! `D(m) = ∫_0^∞ P(t m) t³ dt` (seeds/000 Eq. 36) has the closed form of seeds/000 Eq. 38 with the quadratic
//! forms of `Q⁻¹` in place of the diagonal ones; the projected area and the exact visible-normal
//! sampler are those of [`GaussianGradient`] with the spread `K/√2`, `K Kᵀ = Q`.

use super::gaussian_gradient::{GaussianGradient, Spread};
use super::MicrofacetDistribution;
use crate::error::{Error, ErrorKind, Result};
use crate::limits::ROUGHNESS_RANGE;
use crate::special::{erfc, erfcx};
use glam::{DMat3, DVec3};
use std::f64::consts::PI;

/// A symmetric `Q` whose smallest pivot is below this fraction of its largest diagonal entry is
/// refused: the distribution would be a height field along an oblique axis.
const MIN_PIVOT: f64 = 1e-12;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpssMatrix {
    /// `Q` (symmetric positive definite), local frame.
    q: DMat3,
    /// Lower-triangular Cholesky factor, `K Kᵀ = Q`.
    k: DMat3,
    /// `adj(Q) = det(Q) Q⁻¹`, which stays finite as `Q` approaches a height field.
    adjugate: DMat3,
    det: f64,
}

impl GpssMatrix {
    /// From the symmetric `Q` (only its lower triangle is read); `name` labels errors.
    pub fn new(q: DMat3, name: &str) -> Result<GpssMatrix> {
        let bad = |m: String| Error::new(ErrorKind::InvalidArgument, format!("{name}: {m}"));
        let q = DMat3::from_cols(
            DVec3::new(q.x_axis.x, q.x_axis.y, q.x_axis.z),
            DVec3::new(q.x_axis.y, q.y_axis.y, q.y_axis.z),
            DVec3::new(q.x_axis.z, q.y_axis.z, q.z_axis.z),
        );
        if !q.is_finite() {
            return Err(bad(format!("the matrix must be finite, got {q}")));
        }
        // The roughness along the frame's axes (α² on Q's diagonal) within ROUGHNESS_RANGE, as
        // for alpha_u, alpha_v and alpha_z: beyond it the normals no longer change, and D's
        // det(Q)^{3/2} overflows near α ~ 1e34 (found by fuzzing: a field's anisotropy gave
        // α ~ 1e37 and D = +inf).
        let largest = q.x_axis.x.max(q.y_axis.y).max(q.z_axis.z);
        if largest > ROUGHNESS_RANGE.1 * ROUGHNESS_RANGE.1 {
            return Err(bad(format!("the roughness along the frame's axes reaches {:e}, above {:e}: the normals no longer change (α² = {largest:e} on the diagonal of {q})", largest.sqrt(), ROUGHNESS_RANGE.1)));
        }
        // Cholesky, lower: column j of K.
        let scale = q.x_axis.x.max(q.y_axis.y).max(q.z_axis.z);
        let a = |r: usize, c: usize| q.col(c)[r];
        let mut l = [[0.0f64; 3]; 3];
        for j in 0..3 {
            let pivot = a(j, j) - (0..j).map(|p| l[j][p] * l[j][p]).sum::<f64>();
            if !(pivot > MIN_PIVOT * scale) {
                return Err(bad(format!("the matrix must be positive definite, got {q}")));
            }
            l[j][j] = pivot.sqrt();
            for i in j + 1..3 {
                l[i][j] = (a(i, j) - (0..j).map(|p| l[i][p] * l[j][p]).sum::<f64>()) / l[j][j];
            }
        }
        let k = DMat3::from_cols(DVec3::new(l[0][0], l[1][0], l[2][0]), DVec3::new(0.0, l[1][1], l[2][1]), DVec3::new(0.0, 0.0, l[2][2]));
        let det = (l[0][0] * l[1][1] * l[2][2]).powi(2);
        // The cofactors (Q is symmetric, so rows and columns agree).
        let adjugate = DMat3::from_cols(q.y_axis.cross(q.z_axis), q.z_axis.cross(q.x_axis), q.x_axis.cross(q.y_axis));
        Ok(GpssMatrix { q, k, adjugate, det })
    }

    /// `Q`.
    pub fn q(&self) -> DMat3 {
        self.q
    }

    fn gradient(&self) -> GaussianGradient {
        GaussianGradient { spread: Spread::Matrix(self.k) }
    }

    /// The largest and smallest eigenvalue bounds of `Q` (Gershgorin discs): the roughness
    /// `alpha² ∈ [lo, hi]` along any direction.
    pub fn alpha_squared_range(&self) -> (f64, f64) {
        let rows = [0, 1, 2].map(|i| {
            let row = self.q.row(i);
            let off: f64 = (0..3).filter(|&j| j != i).map(|j| row[j].abs()).sum();
            (row[i] - off, row[i] + off)
        });
        let lo = rows.iter().map(|r| r.0).fold(f64::INFINITY, f64::min).max(0.0);
        let hi = rows.iter().map(|r| r.1).fold(0.0, f64::max);
        (lo, hi)
    }
}

impl MicrofacetDistribution for GpssMatrix {
    /// seeds/000 Eq. 38 with `Q⁻¹`: with `a = mᵀ adj(Q) m`, `b = mᵀ adj(Q) e_z`,
    /// `c = adj(Q)_zz` (seeds/000 Eq. 38's `A, B, C` times `det Q`), `β = b / sqrt(det(Q) a)`,
    /// `D = det(Q)^{3/2} e^{-c/det Q} / (π^{3/2} a²) [(β² + 1)/2 + (√π/2) β (β² + 3/2) erfcx(-β)]`.
    /// For `β >= 0` the `erfc` term carries `e^{E}` with `E = −wᵀ Q w / a`, `w = e_z × m`
    /// (Cauchy–Schwarz in the `Q⁻¹` metric: `ac − b² = det(Q) wᵀ Q w`), which neither overflows nor
    /// cancels for nearly flat `Q`.
    fn d(&self, m: DVec3) -> f64 {
        let adj = self.adjugate;
        let a = m.dot(adj * m);
        let b = m.dot(adj * DVec3::Z);
        let c = adj.z_axis.z;
        let det = self.det;
        let beta = b / (det * a).sqrt();
        let prefactor = det.powf(1.5) / (PI.powf(1.5) * a * a);
        let half_sqrt_pi = 0.5 * PI.sqrt();
        let poly = beta * (beta * beta + 1.5);
        let tail = (-c / det).exp();
        let bracket = if beta >= 0.0 {
            let w = DVec3::Z.cross(m);
            let e = -w.dot(self.q * w) / a;
            tail * 0.5 * (beta * beta + 1.0) + half_sqrt_pi * poly * e.exp() * erfc(-beta)
        } else {
            tail * (0.5 * (beta * beta + 1.0) + half_sqrt_pi * poly * erfcx(-beta))
        };
        (prefactor * bracket).max(0.0)
    }

    /// `E[max(0, w·g)]` with `s(w) = sqrt(wᵀ Q w)` (seeds/000 Eq. 32 with `Q`).
    fn projected_area(&self, w: DVec3) -> f64 {
        self.gradient().projected_area(w)
    }

    /// Exact, through the gradient-space identity with the spread `K/√2`.
    fn sample_visible(&self, wi: DVec3, u: [f64; 3]) -> Option<DVec3> {
        self.gradient().sample_visible(wi, u)
    }
}
