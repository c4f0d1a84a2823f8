//! Linearly transformed microfacet distributions (seeds/001 §4): a height-field microsurface
//! transformed in the tangent plane by `M = [[a, c], [b, d]]` (seeds/001 Eq. 9; `M` maps the
//! microsurface's tangent coordinates, `x` along the host's tangent). Normals transform with
//! `M^{−T}`, directions with `M`.
//!
//! - `D_M(m) = |det M| / |M^T m|⁴ · D(M^T m / |M^T m|)` (seeds/001 Eq. 22), normalised for every `M`.
//! - `G1_M(v, m) = G1(M^{−1} v/|M^{−1} v|, M^T m/|M^T m|)` (seeds/001 Eq. 12), so Smith's Λ is
//!   `Λ_M(v) = Λ(M^{−1} v/|·|)` and the projected area, homogeneous of degree 1 in its
//!   argument, is `A_M(v) = A(M^{−1} v)`.
//! - Visible normals (seeds/001 Eq. 28): `w = M^{−1} v/|·|`, a visible normal `u` of the base seen from
//!   `w`, then `m = M^{−T} u/|·|`. Exact whenever the base sampler is; the same holds for
//!   `D(m)(m·n)` (seeds/001 Eqs. 25–26).
//!
//! `M = diag(α/α_u, α/α_v)` turns an isotropic shape-invariant base of roughness `α` into the
//! classic anisotropic one (seeds/001 Eq. 29); [`Ltmd::stretch`] is the area-preserving `M_s` of seeds/001 Eq. 31.
//! `M` is a plain value: a per-query matrix (e.g. from a tension map, §5.1) is just another
//! `Ltmd`.

use super::{Beckmann, Ggx, Gtr, MicrofacetDistribution};
use crate::error::{Error, ErrorKind, Result};
use glam::{DMat2, DVec2, DVec3};

/// The distributions a transform applies to: the height fields (their `D` vanishes below the
/// horizon, so `M^{−T}` keeps every normal in its hemisphere).
// GTR's inline Gauss–Jacobi mixture makes its variant large; distributions stay `Copy` values
// (the tracker's bounds copy them), so it is not boxed.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LtmdBase {
    Beckmann(Beckmann),
    Ggx(Ggx),
    Gtr(Gtr),
}

impl LtmdBase {
    fn ndf(&self) -> &dyn MicrofacetDistribution {
        match self {
            LtmdBase::Beckmann(x) => x,
            LtmdBase::Ggx(x) => x,
            LtmdBase::Gtr(x) => x,
        }
    }

    /// True when the base has no preferred tangential direction.
    pub fn is_isotropic(&self) -> bool {
        match self {
            LtmdBase::Beckmann(b) => b.alpha_u == b.alpha_v,
            LtmdBase::Ggx(g) => g.alpha_u == g.alpha_v,
            LtmdBase::Gtr(_) => true,
        }
    }

    /// The base with its roughness replaced by the largest (`hi`) or smallest tangential one.
    fn isotropic_bound(&self, hi: bool) -> LtmdBase {
        let pick = |u: f64, v: f64| if hi { u.max(v) } else { u.min(v) };
        match *self {
            LtmdBase::Beckmann(b) => {
                let a = pick(b.alpha_u, b.alpha_v);
                LtmdBase::Beckmann(Beckmann { alpha_u: a, alpha_v: a })
            }
            LtmdBase::Ggx(g) => {
                let a = pick(g.alpha_u, g.alpha_v);
                LtmdBase::Ggx(Ggx { alpha_u: a, alpha_v: a })
            }
            LtmdBase::Gtr(g) => LtmdBase::Gtr(g),
        }
    }

    /// A bound of `|∇_w A(w)|` for the homogeneous projected area `A(w) = ∫ <w, m> D dm`
    /// (its gradient is `∫_{w·m>0} m D dm`). Beckmann: `E|g| <= sqrt(1 + (α_u² + α_v²)/2)`
    /// for the Gaussian gradients `g` (seeds/000 Eq. 37); GGX: with
    /// `A = (w_z + sqrt(w_z² + |α∘w_t|²))/2` the gradient is at most `sqrt(1 + α_max²/4)`;
    /// GTR: `∫ D dm`.
    pub fn gradient_bound(&self) -> f64 {
        match *self {
            LtmdBase::Beckmann(b) => (1.0 + 0.5 * (b.alpha_u * b.alpha_u + b.alpha_v * b.alpha_v)).sqrt(),
            LtmdBase::Ggx(g) => (1.0 + 0.25 * g.alpha_u.max(g.alpha_v).powi(2)).sqrt(),
            LtmdBase::Gtr(g) => g.total_mass(),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ltmd {
    pub base: LtmdBase,
    /// `M` of seeds/001 Eq. 9 (its 2×2 tangent block; the `z` row and column are the identity).
    pub transform: DMat2,
    inverse: DMat2,
    abs_det: f64,
}

/// The largest entry of a microsurface transform: it scales the base's slopes, and beyond it
/// the roughness leaves every useful range while `|Mᵀm|⁴` in `D_M` nears overflow.
const MAX_TRANSFORM_ENTRY: f64 = 1e12;

impl Ltmd {
    /// `base` transformed by `transform`; `M` must be finite and invertible (the error names
    /// the parameter `transform`).
    pub fn new(base: LtmdBase, transform: DMat2) -> Result<Ltmd> {
        let entries = transform.to_cols_array();
        let scale = entries.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let det = transform.determinant();
        // An (almost) singular M flattens the microsurface into a line: D_M is not a density.
        // Entries beyond MAX_TRANSFORM_ENTRY overflow D_M's |Mᵀm|⁴ (found by fuzzing: entries
        // 2e155 passed with an infinite determinant, and D was NaN).
        if !entries.iter().all(|x| x.is_finite()) || scale > MAX_TRANSFORM_ENTRY || !(det.abs() > 1e-12 * scale * scale) {
            return Err(Error::new(
                ErrorKind::InvalidValue,
                format!(
                    "the microsurface transform (\"transform_xx\", \"transform_xy\", \"transform_yx\", \"transform_yy\") must be a finite invertible matrix with entries within ±{MAX_TRANSFORM_ENTRY:e}, got xx = {}, xy = {}, yx = {}, yy = {} (determinant {det})",
                    entries[0], entries[2], entries[1], entries[3]
                ),
            ));
        }
        Ok(Ltmd { base, transform, inverse: transform.inverse(), abs_det: det.abs() })
    }

    /// The stretch `M_s` of seeds/001 Eq. 31, `s ∈ (−1, 1)`: `diag(1/(1 − s), 1 − s)` for `s >= 0`,
    /// `diag(1 + s, 1/(1 + s))` below; `det M_s = 1`.
    pub fn stretch(base: LtmdBase, s: f64) -> Result<Ltmd> {
        Ltmd::new(base, Ltmd::stretch_matrix(s)?)
    }

    /// `M_s` of seeds/001 Eq. 31.
    pub fn stretch_matrix(s: f64) -> Result<DMat2> {
        if !(s > -1.0 && s < 1.0) {
            return Err(Error::new(ErrorKind::InvalidValue, format!("parameter \"stretch\" must lie in (-1, 1), got {s}")));
        }
        let diag = if s >= 0.0 { DVec2::new(1.0 / (1.0 - s), 1.0 - s) } else { DVec2::new(1.0 + s, 1.0 / (1.0 + s)) };
        Ok(DMat2::from_diagonal(diag))
    }

    /// Classic anisotropy from an isotropic base of roughness `alpha` (seeds/001 Eq. 29):
    /// `M = diag(α/α_u, α/α_v)`.
    pub fn anisotropic(base: LtmdBase, alpha: f64, alpha_u: f64, alpha_v: f64) -> Result<Ltmd> {
        Ltmd::new(base, DMat2::from_diagonal(DVec2::new(alpha / alpha_u, alpha / alpha_v)))
    }

    /// `M^T m` (normals of the transformed surface to normals of the base).
    fn base_normal_of(&self, m: DVec3) -> DVec3 {
        let t = self.transform.transpose() * DVec2::new(m.x, m.y);
        DVec3::new(t.x, t.y, m.z)
    }

    /// `M^{−1} v` (directions of the transformed surface to directions of the base).
    fn base_direction_of(&self, v: DVec3) -> DVec3 {
        let t = self.inverse * DVec2::new(v.x, v.y);
        DVec3::new(t.x, t.y, v.z)
    }

    /// `M^{−T} u` (base normals to normals of the transformed surface).
    fn normal_from_base(&self, u: DVec3) -> DVec3 {
        let t = self.inverse.transpose() * DVec2::new(u.x, u.y);
        DVec3::new(t.x, t.y, u.z)
    }

    /// `A_M(v) = |M^{−1} v| · A(M^{−1} v / |M^{−1} v|)` for the base area `area`.
    fn transformed_area(&self, v: DVec3, area: impl Fn(DVec3) -> f64) -> f64 {
        let w = self.base_direction_of(v);
        let len = w.length();
        if len == 0.0 {
            return 0.0;
        }
        len * area(w / len)
    }

    /// The smallest and largest singular values of `M`.
    pub fn singular_values(&self) -> (f64, f64) {
        let [a, b, c, d] = self.transform.to_cols_array();
        // Singular values of a 2×2 matrix from its Frobenius norm and determinant.
        let frob2 = a * a + b * b + c * c + d * d;
        let det = self.abs_det;
        let root = ((frob2 - 2.0 * det) * (frob2 + 2.0 * det)).max(0.0).sqrt();
        let hi = (0.5 * (frob2 + root)).sqrt();
        (det / hi, hi)
    }

    /// The same base under `σ I`: for an isotropic base its projected area is `A(v_t/σ, v_z)`,
    /// which bounds `A_M` from above with `σ = σ_min(M)` and from below with `σ_max(M)` (the
    /// area is convex and even in `v_t`, hence grows with `|v_t|`).
    pub fn isotropic_bound(&self, hi: bool) -> Ltmd {
        let (lo_sv, hi_sv) = self.singular_values();
        let sigma = if hi { lo_sv } else { hi_sv };
        let base = self.base.isotropic_bound(hi);
        Ltmd { base, transform: DMat2::from_diagonal(DVec2::splat(sigma)), inverse: DMat2::from_diagonal(DVec2::splat(1.0 / sigma)), abs_det: sigma * sigma }
    }

    /// True when `D_M` is rotation invariant: an isotropic base under a similarity.
    pub fn is_isotropic(&self) -> bool {
        let (lo, hi) = self.singular_values();
        self.base.is_isotropic() && lo == hi
    }

    /// Bound of the great-circle derivative of the projected area: `∇A_M(v) = M^{−T} ∇A(M^{−1}v)`,
    /// so `|∇A_M| <= |M^{−1}|₂ · gradient_bound(base)`.
    pub fn projected_area_lipschitz(&self) -> f64 {
        let (lo, _) = self.singular_values();
        self.base.gradient_bound() / lo
    }
}

impl MicrofacetDistribution for Ltmd {
    /// seeds/001 Eq. 22.
    fn d(&self, m: DVec3) -> f64 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let u = self.base_normal_of(m);
        let len2 = u.length_squared();
        self.abs_det / (len2 * len2) * self.base.ndf().d(u / len2.sqrt())
    }

    /// seeds/001 Eq. 12 in projected-area form: `A_M(v) = A(M^{−1} v)`.
    fn projected_area(&self, w: DVec3) -> f64 {
        self.transformed_area(w, |x| self.base.ndf().projected_area(x))
    }

    fn sampling_projected_area(&self, w: DVec3) -> f64 {
        self.transformed_area(w, |x| self.base.ndf().sampling_projected_area(x))
    }

    /// seeds/001 Eq. 28 through the transform.
    fn sample_visible(&self, wi: DVec3, u: [f64; 3]) -> Option<DVec3> {
        let w = self.base_direction_of(wi).try_normalize()?;
        let u_base = self.base.ndf().sample_visible(w, u)?;
        let m = self.normal_from_base(u_base).try_normalize()?;
        // Rounding can leave a grazing sample a hair behind the visibility plane.
        (wi.dot(m) > 0.0).then_some(m)
    }

    /// seeds/001 Eqs. 25–26.
    fn sample_normal(&self, u: [f64; 2]) -> Option<DVec3> {
        let u_base = self.base.ndf().sample_normal(u)?;
        self.normal_from_base(u_base).try_normalize()
    }
}
