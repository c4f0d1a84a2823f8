//! Mean functions of the GPIS: signed-distance functions (`f > 0` outside / above).

use glam::{DVec2, DVec3};

/// The mean `μ` of the Gaussian process: a signed distance function of the mean surface
/// (crate convention: `f > 0` outside / above, local frame normal = `+z`). `gradient` must be
/// the exact gradient of `value` (it is the mean of `∇f`, used by Renewal+ conditioning and
/// normal sampling, seeds/004 Eq. 6).
pub trait MeanSdf {
    /// `μ(p)`.
    fn value(&self, p: DVec3) -> f64;
    /// `∇μ(p)`.
    fn gradient(&self, p: DVec3) -> DVec3;
    /// Texture coordinates of the mean surface's point closest to `p`, for fields painted over
    /// the surface (none: zero).
    fn uv(&self, _p: DVec3) -> DVec2 {
        DVec2::ZERO
    }
}

/// The plane `μ(p) = p.z − height`, gradient `+z`: the planar GPIS of seeds/000 Fig. 7 / 10.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Plane {
    /// Height of the mean plane along `+z`.
    pub height: f64,
}

impl MeanSdf for Plane {
    fn value(&self, p: DVec3) -> f64 {
        p.z - self.height
    }
    fn gradient(&self, _p: DVec3) -> DVec3 {
        DVec3::Z
    }
}

/// The sphere `μ(p) = |p − center| − radius`. At the center the gradient is taken as `+z`.
/// (The kernel axes stay fixed in the frame of the caller, so an anisotropic kernel on a
/// sphere is anisotropic in world axes, not relative to the sphere's normal.)
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    pub center: DVec3,
    pub radius: f64,
}

impl MeanSdf for Sphere {
    fn value(&self, p: DVec3) -> f64 {
        (p - self.center).length() - self.radius
    }
    fn gradient(&self, p: DVec3) -> DVec3 {
        (p - self.center).try_normalize().unwrap_or(DVec3::Z)
    }
}

impl<T: MeanSdf + ?Sized> MeanSdf for &T {
    fn value(&self, p: DVec3) -> f64 {
        (**self).value(p)
    }
    fn gradient(&self, p: DVec3) -> DVec3 {
        (**self).gradient(p)
    }
}
