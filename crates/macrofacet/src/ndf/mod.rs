//! Normal distribution functions on the whole sphere of directions.
//!
//! Conventions shared by every distribution here:
//! - The local frame has the geometric normal at `+z` ([`crate::frame`]).
//! - `D(m)` is defined for every unit `m` on the sphere; height-field NDFs (Beckmann, GGX) vanish
//!   for `m.z <= 0`, the generalized macrofacet does not (seeds/000, Sec. 4.2.2).
//! - `wi` points *away* from the surface, toward where light arrives from / the viewer
//!   (Mitsuba 3's `wi`; pbrt-v4 names it `wo`). A ray propagating along `d` sees the flakes from
//!   `wi = -d`.
//! - `projected_area(w) = ∫ <w, m> D(m) dm` with `<a, b> = max(0, a·b)`. With the propagation
//!   direction `d`, the paper's projected area is `sigma(d) = projected_area(-d) = Lambda(d) cos θ_d`
//!   (seeds/000 Eq. 8 / 31).
//! - `lambda(w)` is Smith's Lambda extended to the whole sphere, `Lambda(-w) = -1 - Lambda(w)`, so
//!   that `projected_area(w) = (1 + Lambda(w)) cos θ_w` for every `w` (design notes).

mod beckmann;
mod gaussian_gradient;
mod ggx;
mod gpss;
mod gpss_matrix;
mod gtr;
mod ltmd;
mod mixture;
mod normal_mixture;

pub use beckmann::Beckmann;
pub use ggx::Ggx;
pub use gpss::Gpss;
pub use gpss_matrix::GpssMatrix;
pub use gtr::{Gtr, GtrLambda};
pub use ltmd::{Ltmd, LtmdBase};
pub use mixture::BeckmannUniformMixture;
pub use normal_mixture::NormalUniformMixture;

use glam::DVec3;

/// Which side of a range a bound holds on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    Upper,
    Lower,
}

impl Side {
    /// `+1` for an upper bound, `−1` for a lower one: the direction in which a margin widens it.
    pub fn sign(self) -> f64 {
        match self {
            Side::Upper => 1.0,
            Side::Lower => -1.0,
        }
    }
}

/// A microfacet (or microflake) normal distribution, in literature notation.
pub trait MicrofacetDistribution {
    /// The NDF `D(m)` (per steradian, normalised by `∫ D(m) (m·n) dm = 1`, seeds/000 Eq. 39 with `ω = n`).
    fn d(&self, m: DVec3) -> f64;

    /// `∫ <w, m> D(m) dm`, the area of the flakes seen from `w` per unit macro-area.
    fn projected_area(&self, w: DVec3) -> f64;

    /// [`Self::projected_area`]`(wi)` when flakes are visible from `wi`; `None` when it is below
    /// the smallest normal `f64`. There `D_wi = <wi, m> D / σ(wi)` (seeds/000 Eq. 12) is `0/0` or has
    /// lost its precision, and the visible-normal samplers find nothing: every density, value and
    /// sample of the phase function treats such a `wi` as seeing no flake.
    fn visible_area(&self, wi: DVec3) -> Option<f64> {
        let area = self.projected_area(wi);
        (area >= f64::MIN_POSITIVE).then_some(area)
    }

    /// Smith's `Lambda(w)`, extended to the whole sphere. Infinite at the horizon.
    /// Identity used: `Lambda(w) cos θ_w = projected_area(-w)` (seeds/000 Eq. 8 with `d = w`);
    /// below the horizon through `Λ(w) = −1 − Λ(−w)` (seeds/000 Eq. 39), which the two quotients
    /// break where `w_z` is subnormal and both areas lose their digits (found by fuzzing: GTR at
    /// `w_z = −1e-320` gave a sum of −1.0074).
    fn lambda(&self, w: DVec3) -> f64 {
        if w.z < 0.0 {
            return -1.0 - self.projected_area(w) / -w.z;
        }
        self.projected_area(-w) / w.z
    }

    /// Samples a normal from the visible-normal distribution `D_wi(m) = <wi, m> D(m) /
    /// projected_area(wi)` (seeds/000 Eq. 12) with three uniform numbers in `[0, 1)`. `None` when no flake
    /// is visible from `wi` (zero projected area).
    fn sample_visible(&self, wi: DVec3, u: [f64; 3]) -> Option<DVec3>;

    /// The projected area that normalises the visible normals [`Self::sample_visible`] draws,
    /// `∫ <w, m> D(m) dm` of this `D`. It equals [`Self::projected_area`] unless the
    /// distribution reports a Smith Λ that is a model rather than the projected area of its
    /// `D` (GTR with Dimov's Λ, seeds/001 Appendix A); then `eval/pdf` of a phase sample
    /// measures that inconsistency instead of hiding it.
    fn sampling_projected_area(&self, w: DVec3) -> f64 {
        self.projected_area(w)
    }

    /// Samples `m ∝ D(m) (m·n)` (the classic NDF sampling that seeds/001 Eqs. 25–26 transform)
    /// with two uniforms; `None` when the distribution has no such sampler (normals below the
    /// horizon).
    fn sample_normal(&self, u: [f64; 2]) -> Option<DVec3> {
        let _ = u;
        None
    }

    /// The density of [`Self::sample_visible`] per solid angle of `m`: `D_wi(m)`.
    fn pdf_visible(&self, wi: DVec3, m: DVec3) -> f64 {
        let cos = wi.dot(m);
        if cos <= 0.0 {
            return 0.0;
        }
        // cos (D / area): the product cos D underflows for grazing m before the quotient does;
        // an area below the smallest normal f64 sees no flake (as in `visible_area`).
        let area = self.sampling_projected_area(wi);
        if area >= f64::MIN_POSITIVE {
            cos * (self.d(m) / area)
        } else {
            0.0
        }
    }
}

/// The distributions a medium can use, dispatched without dynamic allocation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ndf {
    Beckmann(Beckmann),
    Ggx(Ggx),
    Gpss(Gpss),
    /// A full local anisotropy (spatially varying media; built per query, not by name).
    GpssMatrix(GpssMatrix),
    Gtr(Gtr),
    Ltmd(Ltmd),
}

impl MicrofacetDistribution for Ndf {
    fn d(&self, m: DVec3) -> f64 {
        match self {
            Ndf::Beckmann(x) => x.d(m),
            Ndf::Ggx(x) => x.d(m),
            Ndf::Gpss(x) => x.d(m),
            Ndf::GpssMatrix(x) => x.d(m),
            Ndf::Gtr(x) => x.d(m),
            Ndf::Ltmd(x) => x.d(m),
        }
    }
    fn projected_area(&self, w: DVec3) -> f64 {
        match self {
            Ndf::Beckmann(x) => x.projected_area(w),
            Ndf::Ggx(x) => x.projected_area(w),
            Ndf::Gpss(x) => x.projected_area(w),
            Ndf::GpssMatrix(x) => x.projected_area(w),
            Ndf::Gtr(x) => x.projected_area(w),
            Ndf::Ltmd(x) => x.projected_area(w),
        }
    }
    fn lambda(&self, w: DVec3) -> f64 {
        match self {
            Ndf::Beckmann(x) => x.lambda(w),
            Ndf::Ggx(x) => x.lambda(w),
            Ndf::Gpss(x) => x.lambda(w),
            Ndf::GpssMatrix(x) => x.lambda(w),
            Ndf::Gtr(x) => x.lambda(w),
            Ndf::Ltmd(x) => x.lambda(w),
        }
    }
    fn sample_visible(&self, wi: DVec3, u: [f64; 3]) -> Option<DVec3> {
        match self {
            Ndf::Beckmann(x) => x.sample_visible(wi, u),
            Ndf::Ggx(x) => x.sample_visible(wi, u),
            Ndf::Gpss(x) => x.sample_visible(wi, u),
            Ndf::GpssMatrix(x) => x.sample_visible(wi, u),
            Ndf::Gtr(x) => x.sample_visible(wi, u),
            Ndf::Ltmd(x) => x.sample_visible(wi, u),
        }
    }
    fn sampling_projected_area(&self, w: DVec3) -> f64 {
        match self {
            Ndf::Beckmann(x) => x.sampling_projected_area(w),
            Ndf::Ggx(x) => x.sampling_projected_area(w),
            Ndf::Gpss(x) => x.sampling_projected_area(w),
            Ndf::GpssMatrix(x) => x.sampling_projected_area(w),
            Ndf::Gtr(x) => x.sampling_projected_area(w),
            Ndf::Ltmd(x) => x.sampling_projected_area(w),
        }
    }
    fn sample_normal(&self, u: [f64; 2]) -> Option<DVec3> {
        match self {
            Ndf::Beckmann(x) => x.sample_normal(u),
            Ndf::Ggx(x) => x.sample_normal(u),
            Ndf::Gpss(x) => x.sample_normal(u),
            Ndf::GpssMatrix(x) => x.sample_normal(u),
            Ndf::Gtr(x) => x.sample_normal(u),
            Ndf::Ltmd(x) => x.sample_normal(u),
        }
    }
    fn pdf_visible(&self, wi: DVec3, m: DVec3) -> f64 {
        match self {
            Ndf::Beckmann(x) => x.pdf_visible(wi, m),
            Ndf::Ggx(x) => x.pdf_visible(wi, m),
            Ndf::Gpss(x) => x.pdf_visible(wi, m),
            Ndf::GpssMatrix(x) => x.pdf_visible(wi, m),
            Ndf::Gtr(x) => x.pdf_visible(wi, m),
            Ndf::Ltmd(x) => x.pdf_visible(wi, m),
        }
    }
}

/// Roughness from the squared-exponential GP kernel: `alpha = sqrt(2) sigma / l` (seeds/000 Eq. 4).
/// An infinite correlation length gives `alpha = 0` (height field along that axis).
pub fn alpha_from_kernel(sigma: f64, lengthscale: f64) -> f64 {
    std::f64::consts::SQRT_2 * sigma / lengthscale
}

impl Ndf {
    /// Isotropic distributions with the largest and the smallest tangential roughness of this
    /// one (same `alpha_z`). The projected area seen from `w` grows with the roughness along
    /// `w` — for Gaussian gradients `E[max(0, w_z + s Z/√2)]` grows with `s = |α ∘ w|`
    /// (seeds/000 Eq. 32), for GGX `(w_z + sqrt(t² + w_z²))/2` grows with `t²` — so the two
    /// bound the projected area for every azimuth of `w`, whatever the tangent.
    pub fn isotropic_envelope(&self) -> (Ndf, Ndf) {
        match *self {
            Ndf::Beckmann(b) => {
                let (hi, lo) = (b.alpha_u.max(b.alpha_v), b.alpha_u.min(b.alpha_v));
                (Ndf::Beckmann(Beckmann { alpha_u: hi, alpha_v: hi }), Ndf::Beckmann(Beckmann { alpha_u: lo, alpha_v: lo }))
            }
            Ndf::Ggx(g) => {
                let (hi, lo) = (g.alpha_u.max(g.alpha_v), g.alpha_u.min(g.alpha_v));
                (Ndf::Ggx(Ggx { alpha_u: hi, alpha_v: hi }), Ndf::Ggx(Ggx { alpha_u: lo, alpha_v: lo }))
            }
            Ndf::Gpss(g) => {
                let (hi, lo) = (g.alpha_x.max(g.alpha_y), g.alpha_x.min(g.alpha_y));
                (
                    Ndf::Gpss(Gpss { alpha_x: hi, alpha_y: hi, alpha_z: g.alpha_z }),
                    Ndf::Gpss(Gpss { alpha_x: lo, alpha_y: lo, alpha_z: g.alpha_z }),
                )
            }
            Ndf::GpssMatrix(g) => {
                // s(w)² = wᵀ Q w lies between Q's eigenvalue bounds (times |w|² = 1).
                let (lo, hi) = g.alpha_squared_range();
                let iso = |a2: f64| Ndf::Gpss(Gpss { alpha_x: a2.sqrt(), alpha_y: a2.sqrt(), alpha_z: a2.sqrt() });
                (iso(hi), iso(lo))
            }
            Ndf::Gtr(g) => (Ndf::Gtr(g), Ndf::Gtr(g)),
            Ndf::Ltmd(l) => (Ndf::Ltmd(l.isotropic_bound(true)), Ndf::Ltmd(l.isotropic_bound(false))),
        }
    }

    /// A bound of `|d/dθ projected_area(w(θ))|` for `w` moving along any great circle.
    /// Gaussian gradients: `|∇_w E[max(0, w·g)]| <= E|g| <= sqrt(E|g|²) = sqrt(1 + Σα²/2)`.
    /// GGX: the derivative of `(cos θ + sqrt(α² sin² θ + cos² θ))/2` is at most `(1 + max(1, α))/2`
    /// in magnitude (the root's derivative is `(α² − 1) sin θ cos θ / root`, and the root is at
    /// least `|cos θ|` and `α |sin θ|`); anisotropy is covered by the largest `α`.
    pub fn projected_area_lipschitz(&self) -> f64 {
        let gaussian = |a: DVec3| (1.0 + 0.5 * a.length_squared()).sqrt();
        match *self {
            Ndf::Beckmann(b) => gaussian(DVec3::new(b.alpha_u, b.alpha_v, 0.0)),
            Ndf::Ggx(g) => 0.5 * (1.0 + g.alpha_u.max(g.alpha_v).max(1.0)),
            Ndf::Gpss(g) => gaussian(DVec3::new(g.alpha_x, g.alpha_y, g.alpha_z)),
            // E|g|² = 1 + tr(Cov g) = 1 + tr(Q)/2.
            Ndf::GpssMatrix(g) => (1.0 + 0.5 * (g.q().x_axis.x + g.q().y_axis.y + g.q().z_axis.z)).sqrt(),
            // GTR: |∇A| = |∫_{w·m>0} m D dm| <= ∫ D dm.
            Ndf::Gtr(g) => g.total_mass(),
            Ndf::Ltmd(l) => l.projected_area_lipschitz(),
        }
    }

    /// The upper or lower bound of the projected area over every direction with `w_z` in
    /// `[z[0], z[1]]`, where a closed form makes it exact (isotropic gpss and Beckmann; GGX up
    /// to `α = 1`); `None` otherwise. One evaluation: a caller needing one side (a majorant's
    /// `S_up`) pays for that side only.
    pub fn projected_area_bound(&self, z: [f64; 2], side: Side) -> Option<f64> {
        match self {
            Ndf::Gpss(g) => g.projected_area_bound(z, side),
            Ndf::Beckmann(b) => b.projected_area_bound(z, side),
            Ndf::Ggx(g) => g.projected_area_bound(z, side),
            _ => None,
        }
    }

    /// True when [`MicrofacetDistribution::projected_area`] is the projected area of `D` (false
    /// for GTR with Dimov's Λ), so that a phase sample's `eval/pdf` is the flake's reflectance.
    pub fn lambda_is_projected_area(&self) -> bool {
        match self {
            Ndf::Gtr(g) | Ndf::Ltmd(Ltmd { base: LtmdBase::Gtr(g), .. }) => g.lambda == GtrLambda::Exact,
            _ => true,
        }
    }

    /// True when the distribution has no preferred tangential direction.
    pub fn is_isotropic(&self) -> bool {
        match *self {
            Ndf::Beckmann(b) => b.alpha_u == b.alpha_v,
            Ndf::Ggx(g) => g.alpha_u == g.alpha_v,
            Ndf::Gpss(g) => g.alpha_x == g.alpha_y,
            Ndf::GpssMatrix(_) => false,
            Ndf::Gtr(_) => true,
            Ndf::Ltmd(l) => l.is_isotropic(),
        }
    }
}
