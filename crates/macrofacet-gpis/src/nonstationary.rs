//! The non-stationary kernel of seeds/004 Sec. 6.1 (Paciorek–Schervish, seeds/004 Eqs. 25–26) with a
//! squared-exponential `k^S(t) = exp(−t²/2)`, its local variance `σ(x)` and local anisotropy
//! `Σ(x)` taken from a [`MediumField`] — the same fields the macrofacet medium reads
//! ([`macrofacet::field`]):
//!
//! `k(x, y) = σ(x) σ(y) |Σ(x)|^¼ |Σ(y)|^¼ / |S|^½ · exp(−½ rᵀ S⁻¹ r)`, `S = (Σ(x) + Σ(y))/2`,
//! `r = x − y`.
//!
//! For `Σ(x) = Σ(y)` and `σ(x) = σ(y)` this is the stationary [`SeKernel`] of those parameters,
//! and it is positive semi-definite for any fields (Paciorek and Schervish 2006), which no
//! blend of local stationary kernels guarantees (seeds/004 Sec. 6.1).
//!
//! ## From a field's local parameters to `σ(x)`, `Σ(x)`
//! The macrofacet side treats the medium at `x` as the stationary medium of the local
//! parameters ([`macrofacet::MacrofacetMedium::localized`]); the kernel here is locally that same
//! medium's kernel:
//! - `σ(x)` = the field's `sigma`, else the medium's `σ₀`.
//! - `anisotropy` given: `Σ(x)` is it (world space, lengthscales² on its axes): the same matrix
//!   the macrofacet turns into `Q = 2σ² RᵀΣ⁻¹R`. Only for kernels without a deterministic axis.
//! - otherwise the roughness form: `α(x)` = the field's `alpha`, else the medium's own roughness
//!   `α₀ = √2 σ₀ / l₀`, and `l_i(x) = √2 σ(x) / α_i(x)` (seeds/000 Eq. 4, as
//!   [`SeKernel::from_roughness`]), `Σ(x) = diag(l_i(x)²)`. A field of `σ` alone therefore keeps
//!   the roughness and scales every lengthscale with `σ` — as on the macrofacet side, where the
//!   NDF keeps `α₀`. The axes are those of the gpis kernel: the **world** axes (`alpha =
//!   (α_u, α_v, α_z)` along `x, y, z`), which are the macrofacet's local frame wherever the mean
//!   surface's frame is `(x, y, z)`, e.g. on the plane `z = h` with tangent `+x`. For
//!   frame-aligned anisotropy on curved shapes give `anisotropy` (frame-free on both sides).
//!
//! ## Deterministic axes (height fields)
//! An axis along which the medium's own kernel has an infinite lengthscale (`distribution
//! beckmann`, or `alpha_z = 0`) stays deterministic everywhere: the kernel ignores the
//! displacement's component along it (`Σ` holds a placeholder 1 there) and the field's roughness
//! along it is not read. A field cannot make a finite axis infinite (`alpha_z = 0` on a
//! volumetric kernel) — that would make the kernel vanish between the two kinds of points.
//!
//! ## Derivatives (normals at crossings, Renewal+ memory)
//! `∂k/∂x_i` involves the fields' own derivatives. With `a_i = ∂ ln k/∂x_i`,
//! `b_j = ∂ ln k/∂y_j`, `u = S⁻¹ r`, `A = Σ(x)`, `B = Σ(y)`, `A_i = ∂_i Σ(x)`,
//! `B_j = ∂_j Σ(y)` (and `m_i` = 1 on random axes, 0 on deterministic ones):
//!
//! - `a_i = ∂_iσ(x)/σ(x) + ¼ tr(A⁻¹A_i) − ¼ tr(S⁻¹A_i) − m_i u_i + ¼ uᵀA_i u`
//! - `b_j = ∂_jσ(y)/σ(y) + ¼ tr(B⁻¹B_j) − ¼ tr(S⁻¹B_j) + m_j u_j + ¼ uᵀB_j u`
//! - `c_ij = ∂²ln k/∂x_i∂y_j = m_i m_j S⁻¹_ij + ⅛ tr(S⁻¹B_j S⁻¹A_i) + ½ m_i (S⁻¹B_j u)_i
//!   − ½ m_j (S⁻¹A_i u)_j − ¼ uᵀA_i S⁻¹B_j u`
//!
//! and `cov(∂_i f(x), f(y)) = k a_i`, `cov(f(x), ∂_j f(y)) = k b_j`,
//! `cov(∂_i f(x), ∂_j f(y)) = k (a_i b_j + c_ij)`: the stationary table of [`SeKernel`] when the
//! fields do not vary. The fields' derivatives at the points of derivative functionals come from
//! central differences of the field with a step of `10⁻⁴` of the shortest local lengthscale
//! ([`GRADIENT_STEP`]). A field that is constant there gives exactly zero and the stationary
//! formulas, bit for bit. At a discontinuity of a field (a stepped `σ`) realizations jump and
//! have no gradient; within one step of it the differences are large, which affects normals at
//! crossings that close to the discontinuity only.

use super::kernel::{Covariance, Functional, SeKernel};
use super::mean::MeanSdf;
use macrofacet::error::{Error, ErrorKind, Result};
use macrofacet::field::{LocalParams, MediumField};
use macrofacet::ndf::GpssMatrix;
use macrofacet::surface::SurfacePoint;
use glam::{DMat3, DVec3};

/// The fields' derivatives come from central differences with steps of this fraction of the
/// shortest local lengthscale: truncation `O(h²)` ≈ 1e-8 relative for fields that vary over a
/// lengthscale, rounding ≈ 1e-16/1e-4 (or 1e-7/1e-4 for a host's `f32` grid: 1e-3 of the
/// kernel's own slope term).
const GRADIENT_STEP: f64 = 1e-4;

/// The Paciorek–Schervish kernel of a field around a mean (module documentation).
pub struct FieldKernel<'a, M: MeanSdf, F: MediumField> {
    /// The medium's own kernel: `σ₀`, `l₀`, and which axes are deterministic.
    base: SeKernel,
    mean: &'a M,
    field: &'a F,
    /// The largest `σ` the field may give (the envelope's scale).
    sigma_max: f64,
    /// 1 on random axes, 0 on deterministic ones (`l₀ = ∞`).
    random_axes: DVec3,
}

/// The kernel's data at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalKernel {
    /// What the field returned there.
    pub params: LocalParams,
    /// `σ(x)`.
    pub sigma: f64,
    /// `Σ(x)` (world space; 1 on deterministic axes).
    pub matrix: DMat3,
    /// `Σ(x)⁻¹`.
    inverse: DMat3,
    /// `|Σ(x)|`.
    det: f64,
    /// The roughness form: the stationary kernel of the local parameters (`Σ` diagonal).
    stationary: Option<SeKernel>,
    /// The fields' derivatives at `x`, for derivative functionals; `None` where they vanish.
    gradient: Option<FieldGradient>,
}

/// `∇σ(x)` and `∂_i Σ(x)`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct FieldGradient {
    sigma: DVec3,
    matrix: [DMat3; 3],
}

/// The largest `σ` of a GPIS with kernel `base` and `field`: the field's `sigma_max`, else `σ₀`.
pub fn sigma_max<F: MediumField>(base: &SeKernel, field: &F) -> f64 {
    if field.varies() {
        field.sigma_max().unwrap_or(base.sigma)
    } else {
        base.sigma
    }
}

fn invalid(message: String) -> Error {
    Error::new(ErrorKind::InvalidArgument, message)
}

impl<'a, M: MeanSdf, F: MediumField> FieldKernel<'a, M, F> {
    /// The kernel of `field` over `base` (the medium's own kernel, for what the field leaves
    /// unset). `σ_max`: the field's, else `σ₀`.
    pub fn new(base: SeKernel, mean: &'a M, field: &'a F) -> Self {
        let random_axes = DVec3::select(base.lengthscale.cmplt(DVec3::INFINITY), DVec3::ONE, DVec3::ZERO);
        FieldKernel { base, mean, field, sigma_max: sigma_max(&base, field), random_axes }
    }

    /// The field's parameters at `p` (the mean surface there as its [`SurfacePoint`]: `f = μ(p)`,
    /// normal `∇μ/|∇μ|`, tangent `+x`, the first axis of the kernel's frame).
    fn params_at(&self, p: DVec3) -> Result<LocalParams> {
        let normal = self.mean.gradient(p).try_normalize().unwrap_or(DVec3::Z);
        let point = SurfacePoint { f: self.mean.value(p), normal, tangent: DVec3::X, uv: self.mean.uv(p) };
        let params = self.field.at(p, &point)?;
        params.validate("the gpis field")?;
        Ok(params)
    }

    /// `σ(x)`, `Σ(x)` of the local parameters at `p` (module documentation).
    fn local_at(&self, p: DVec3) -> Result<LocalKernel> {
        let params = self.params_at(p)?;
        let sigma = params.sigma.unwrap_or(self.base.sigma);
        // The envelope (seeds/004 Fig. 8) is drawn at σ_max: a larger σ would sample outside it.
        if sigma > self.sigma_max * (1.0 + 1e-12) {
            return Err(invalid(format!("the gpis field's sigma {sigma} at {p} exceeds its sigma_max {}: the field must bound its sigma", self.sigma_max)));
        }
        let (matrix, stationary) = match params.anisotropy {
            Some(anisotropy) => {
                if self.random_axes != DVec3::ONE {
                    return Err(invalid("the gpis field's anisotropy needs a kernel with finite lengthscales (distribution gpss, alpha_z > 0): a height field has a fixed deterministic axis".into()));
                }
                // One acceptance test for Σ on both sides: the macrofacet's GpssMatrix.
                (GpssMatrix::new(anisotropy, "the gpis field's anisotropy")?.q(), None)
            }
            None => {
                let kernel = if params.alpha.is_none() && sigma == self.base.sigma {
                    self.base
                } else {
                    let alpha = params.alpha.unwrap_or_else(|| self.base.roughness()) * self.random_axes;
                    if (0..3).any(|i| self.random_axes[i] == 1.0 && alpha[i] == 0.0) {
                        return Err(invalid(format!("the gpis field's alpha {alpha} at {p} is 0 along an axis where the medium's kernel has a finite lengthscale (a height field needs distribution beckmann or alpha_z = 0 for the medium)")));
                    }
                    SeKernel::from_roughness(sigma, alpha)?
                };
                let l2 = kernel.lengthscale * kernel.lengthscale;
                (DMat3::from_diagonal(DVec3::select(l2.cmplt(DVec3::INFINITY), l2, DVec3::ONE)), Some(kernel))
            }
        };
        let inverse = match stationary {
            // Exact reciprocals, as the stationary kernel's `1/l²`.
            Some(_) => DMat3::from_diagonal(DVec3::ONE / DVec3::new(matrix.x_axis.x, matrix.y_axis.y, matrix.z_axis.z)),
            None => matrix.inverse(),
        };
        Ok(LocalKernel { params, sigma, matrix, inverse, det: matrix.determinant(), stationary, gradient: None })
    }

    /// The fields' derivatives at `p` by central differences (module documentation).
    fn with_gradient(&self, p: DVec3, mut local: LocalKernel) -> Result<LocalKernel> {
        let masked_inverse = DMat3::from_diagonal(self.random_axes) * local.inverse;
        let trace = masked_inverse.x_axis.x + masked_inverse.y_axis.y + masked_inverse.z_axis.z;
        // tr(Σ⁻¹) >= 1/λ_min(Σ): the step is at most GRADIENT_STEP of the shortest lengthscale.
        let h = if trace > 0.0 { GRADIENT_STEP / trace.sqrt() } else { GRADIENT_STEP * local.sigma };
        let mut gradient = FieldGradient { sigma: DVec3::ZERO, matrix: [DMat3::ZERO; 3] };
        for (i, axis) in [DVec3::X, DVec3::Y, DVec3::Z].into_iter().enumerate() {
            let (plus, minus) = (self.local_at(p + h * axis)?, self.local_at(p - h * axis)?);
            gradient.sigma[i] = (plus.sigma - minus.sigma) / (2.0 * h);
            gradient.matrix[i] = (plus.matrix - minus.matrix) * (0.5 / h);
        }
        let zero = gradient.sigma == DVec3::ZERO && gradient.matrix.iter().all(|m| *m == DMat3::ZERO);
        local.gradient = (!zero).then_some(gradient);
        Ok(local)
    }
}

impl<M: MeanSdf, F: MediumField> Covariance for FieldKernel<'_, M, F> {
    type Local = LocalKernel;

    fn local(&self, p: DVec3, derivatives: bool) -> Result<LocalKernel> {
        let local = self.local_at(p)?;
        if derivatives {
            self.with_gradient(p, local)
        } else {
            Ok(local)
        }
    }

    fn covariance(&self, a: &Functional, la: &LocalKernel, b: &Functional, lb: &LocalKernel) -> f64 {
        let same = la.sigma == lb.sigma && la.matrix == lb.matrix;
        let x_gradient = match *a {
            Functional::Partial(_, i) => Some((i, la.gradient)),
            Functional::Value(_) => None,
        };
        let y_gradient = match *b {
            Functional::Partial(_, j) => Some((j, lb.gradient)),
            Functional::Value(_) => None,
        };
        let varies = matches!(x_gradient, Some((_, Some(_)))) || matches!(y_gradient, Some((_, Some(_))));
        if let (true, false, Some(kernel)) = (same, varies, la.stationary) {
            // The stationary kernel of these parameters: the same arithmetic as without a field.
            return kernel.covariance(a, b);
        }
        let m = self.random_axes;
        let r = (a.point() - b.point()) * m;
        let diagonal = |m: DMat3| DVec3::new(m.x_axis.x, m.y_axis.y, m.z_axis.z);
        let (s_inv, prefactor) = if same {
            (la.inverse, 1.0)
        } else if la.stationary.is_some() && lb.stationary.is_some() {
            // Two roughness forms: S is diagonal.
            let s = (diagonal(la.matrix) + diagonal(lb.matrix)) * 0.5;
            (DMat3::from_diagonal(DVec3::ONE / s), (la.det * lb.det).sqrt().sqrt() / s.element_product().sqrt())
        } else {
            let s = (la.matrix + lb.matrix) * 0.5;
            (s.inverse(), (la.det * lb.det).sqrt().sqrt() / s.determinant().sqrt())
        };
        let u = s_inv * r;
        let k = la.sigma * lb.sigma * prefactor * (-0.5 * r.dot(u)).exp();
        let trace = |x: DMat3| x.x_axis.x + x.y_axis.y + x.z_axis.z;
        // a_i, with A_i when the field varies at x.
        let a_i = x_gradient.map(|(i, g)| {
            let mut v = -m[i] * u[i];
            let di = g.map(|g| {
                let ai = g.matrix[i];
                v += g.sigma[i] / la.sigma + 0.25 * trace(la.inverse * ai) - 0.25 * trace(s_inv * ai) + 0.25 * u.dot(ai * u);
                ai
            });
            (i, v, di)
        });
        let b_j = y_gradient.map(|(j, g)| {
            let mut v = m[j] * u[j];
            let dj = g.map(|g| {
                let bj = g.matrix[j];
                v += g.sigma[j] / lb.sigma + 0.25 * trace(lb.inverse * bj) - 0.25 * trace(s_inv * bj) + 0.25 * u.dot(bj * u);
                bj
            });
            (j, v, dj)
        });
        match (a_i, b_j) {
            (None, None) => k,
            (Some((_, a, _)), None) => k * a,
            (None, Some((_, b, _))) => k * b,
            (Some((i, a, ai)), Some((j, b, bj))) => {
                let mut c = m[i] * m[j] * s_inv.col(j)[i];
                if let Some(bj) = bj {
                    c += 0.5 * m[i] * (s_inv * bj * u)[i];
                }
                if let Some(ai) = ai {
                    c -= 0.5 * m[j] * (s_inv * ai * u)[j];
                }
                if let (Some(ai), Some(bj)) = (ai, bj) {
                    c += 0.125 * trace(s_inv * bj * s_inv * ai) - 0.25 * u.dot(ai * s_inv * bj * u);
                }
                k * (a * b + c)
            }
        }
    }

    fn variance(&self, a: &Functional, la: &LocalKernel) -> f64 {
        match (la.stationary, la.gradient, a) {
            (Some(kernel), None, _) | (Some(kernel), _, Functional::Value(_)) => kernel.variance(a),
            _ => self.covariance(a, la, a, la),
        }
    }

    fn sigma(&self, la: &LocalKernel) -> f64 {
        la.sigma
    }

    fn region_sigma(&self) -> f64 {
        self.sigma_max
    }

    fn step_for_correlation(&self, la: &LocalKernel, d: DVec3, rho: f64) -> f64 {
        if let Some(kernel) = la.stationary {
            return kernel.step_for_correlation(d, rho);
        }
        let d = d * self.random_axes;
        let q = d.dot(la.inverse * d);
        if q > 0.0 {
            (-2.0 * rho.ln() / q).sqrt()
        } else {
            f64::INFINITY
        }
    }

    fn random_partial(&self, la: &LocalKernel, i: usize) -> bool {
        self.random_axes[i] == 1.0 || la.gradient.is_some_and(|g| g.sigma[i] != 0.0 || g.matrix[i] != DMat3::ZERO)
    }

    fn params(&self, la: &LocalKernel) -> LocalParams {
        la.params
    }
}
