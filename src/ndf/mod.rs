//! Normal distribution functions on the whole sphere of directions.
//!
//! Conventions shared by every distribution here:
//! - The local frame has the geometric normal at `+z` ([`crate::frame`]).
//! - `D(m)` is defined for every unit `m` on the sphere; height-field NDFs (Beckmann, GGX) vanish
//!   for `m.z <= 0`, the generalized macrofacet does not (seeds/000, Sec. 4.2.2).
//! - `wi` points *away* from the surface, toward where light arrives from / the viewer
//!   (Mitsuba 3 / pbrt). A ray propagating along `d` sees the flakes from `wi = -d`.
//! - `projected_area(w) = ∫ <w, m> D(m) dm` with `<a, b> = max(0, a·b)`. With the propagation
//!   direction `d`, the paper's projected area is `sigma(d) = projected_area(-d) = Lambda(d) cos θ_d`
//!   (Eq. 8 / 31).
//! - `lambda(w)` is Smith's Lambda extended to the whole sphere, `Lambda(-w) = -1 - Lambda(w)`, so
//!   that `projected_area(w) = (1 + Lambda(w)) cos θ_w` for every `w` (design notes).

mod beckmann;
mod gaussian_gradient;
mod ggx;
mod gpss;
mod mixture;

pub use beckmann::Beckmann;
pub use ggx::Ggx;
pub use gpss::Gpss;
pub use mixture::BeckmannUniformMixture;

use glam::DVec3;

/// A microfacet (or microflake) normal distribution, in literature notation.
pub trait MicrofacetDistribution {
    /// The NDF `D(m)` (per steradian, normalised by `∫ D(m) (m·n) dm = 1`, Eq. 39 with `ω = n`).
    fn d(&self, m: DVec3) -> f64;

    /// `∫ <w, m> D(m) dm`, the area of the flakes seen from `w` per unit macro-area.
    fn projected_area(&self, w: DVec3) -> f64;

    /// [`Self::projected_area`]`(wi)` when flakes are visible from `wi`; `None` when it is below
    /// the smallest normal `f64`. There `D_wi = <wi, m> D / σ(wi)` (Eq. 12) is `0/0` or has
    /// lost its precision, and the visible-normal samplers find nothing: every density, value and
    /// sample of the phase function treats such a `wi` as seeing no flake.
    fn visible_area(&self, wi: DVec3) -> Option<f64> {
        let area = self.projected_area(wi);
        (area >= f64::MIN_POSITIVE).then_some(area)
    }

    /// Smith's `Lambda(w)`, extended to the whole sphere. Infinite at the horizon.
    /// Identity used: `Lambda(w) cos θ_w = projected_area(-w)` (Eq. 8 with `d = w`).
    fn lambda(&self, w: DVec3) -> f64 {
        self.projected_area(-w) / w.z
    }

    /// Samples a normal from the visible-normal distribution `D_wi(m) = <wi, m> D(m) /
    /// projected_area(wi)` (Eq. 12) with three uniform numbers in `[0, 1)`. `None` when no flake
    /// is visible from `wi` (zero projected area).
    fn sample_visible(&self, wi: DVec3, u: [f64; 3]) -> Option<DVec3>;

    /// The density of [`Self::sample_visible`] per solid angle of `m`: `D_wi(m)`.
    fn pdf_visible(&self, wi: DVec3, m: DVec3) -> f64 {
        let cos = wi.dot(m);
        if cos <= 0.0 {
            return 0.0;
        }
        // cos (D / area): the product cos D underflows for grazing m before the quotient does.
        self.visible_area(wi).map_or(0.0, |area| cos * (self.d(m) / area))
    }
}

/// The distributions a medium can use, dispatched without dynamic allocation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ndf {
    Beckmann(Beckmann),
    Ggx(Ggx),
    Gpss(Gpss),
}

impl MicrofacetDistribution for Ndf {
    fn d(&self, m: DVec3) -> f64 {
        match self {
            Ndf::Beckmann(x) => x.d(m),
            Ndf::Ggx(x) => x.d(m),
            Ndf::Gpss(x) => x.d(m),
        }
    }
    fn projected_area(&self, w: DVec3) -> f64 {
        match self {
            Ndf::Beckmann(x) => x.projected_area(w),
            Ndf::Ggx(x) => x.projected_area(w),
            Ndf::Gpss(x) => x.projected_area(w),
        }
    }
    fn lambda(&self, w: DVec3) -> f64 {
        match self {
            Ndf::Beckmann(x) => x.lambda(w),
            Ndf::Ggx(x) => x.lambda(w),
            Ndf::Gpss(x) => x.lambda(w),
        }
    }
    fn sample_visible(&self, wi: DVec3, u: [f64; 3]) -> Option<DVec3> {
        match self {
            Ndf::Beckmann(x) => x.sample_visible(wi, u),
            Ndf::Ggx(x) => x.sample_visible(wi, u),
            Ndf::Gpss(x) => x.sample_visible(wi, u),
        }
    }
}

/// Roughness from the squared-exponential GP kernel: `alpha = sqrt(2) sigma / l` (Eq. 4).
/// An infinite correlation length gives `alpha = 0` (height field along that axis).
pub fn alpha_from_kernel(sigma: f64, lengthscale: f64) -> f64 {
    std::f64::consts::SQRT_2 * sigma / lengthscale
}
