//! The squared-exponential kernel of seeds/000 Eq. 1 and its value–gradient covariances
//! (seeds/000 Eq. 2, seeds/004 Eq. 5–6), in closed form.
//!
//! `k(p, q) = σ² exp(−½ Σ_i (p_i − q_i)² / l_i²)` in the local frame (normal = `+z`). Writing
//! `r = p − q` and `w_i = 1/l_i²` (`w_i = 0` for `l_i = +∞`):
//!
//! | pair | covariance |
//! |---|---|
//! | `f(p), f(q)` | `k` |
//! | `f(p), ∂_j f(q)` | `∂k/∂q_j = k w_j r_j` |
//! | `∂_i f(p), f(q)` | `∂k/∂p_i = −k w_i r_i` |
//! | `∂_i f(p), ∂_j f(q)` | `∂²k/∂p_i∂q_j = k (w_i δ_ij − w_i w_j r_i r_j)` |
//!
//! With `r = 0` the value and the gradient at one point are uncorrelated and the gradient
//! components are independent with variances `σ² w_i = σ²/l_i²`; since the roughness is
//! `α_i = √2 σ / l_i` (seeds/000 Eq. 4, seeds/004 Eq. 20 `α = √(−2k''(0))` per unit variance),
//! the slopes have variance `α_i²/2`, Beckmann's. An axis with `l_i = +∞` has a
//! *deterministic* partial derivative (`∂_i f = ∂_i μ`): no correlation loss along it, so
//! `l_z = +∞` makes the GPIS of a plane a height field.

use macrofacet::error::{Error, ErrorKind, Result};
use macrofacet::field::LocalParams;
use glam::DVec3;

/// What the march in function space needs from a covariance: the stationary [`SeKernel`], or
/// the non-stationary kernel of a field ([`super::FieldKernel`]), whose covariances depend on
/// data at each point (its [`Covariance::Local`]), computed once per observation.
pub trait Covariance {
    /// The kernel's data at one point (nothing for a stationary kernel).
    type Local: Copy;
    /// The data at `p`; with `derivatives`, also what covariances of partial derivatives at `p`
    /// need.
    fn local(&self, p: DVec3, derivatives: bool) -> Result<Self::Local>;
    /// `cov(a, b)`; `la`, `lb` are the data at their points.
    fn covariance(&self, a: &Functional, la: &Self::Local, b: &Functional, lb: &Self::Local) -> f64;
    /// `cov(a, a)`.
    fn variance(&self, a: &Functional, la: &Self::Local) -> f64;
    /// The process's standard deviation at the point.
    fn sigma(&self, la: &Self::Local) -> f64;
    /// The largest standard deviation anywhere (the scale of the envelope).
    fn region_sigma(&self) -> f64;
    /// The step `Δt` from the point along `d` whose correlation is `rho` there (`+∞` when the
    /// process is perfectly correlated along `d`).
    fn step_for_correlation(&self, la: &Self::Local, d: DVec3, rho: f64) -> f64;
    /// False when `∂_i f` is deterministic at the point (`∂_i μ`; not conditioned on).
    fn random_partial(&self, la: &Self::Local, i: usize) -> bool;
    /// The field's parameters at the point (none for a stationary kernel).
    fn params(&self, la: &Self::Local) -> LocalParams;
}

/// The squared-exponential kernel: variance `sigma²`, correlation lengths `lengthscale` along
/// the local axes (`+∞` allowed per axis).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeKernel {
    /// Standard deviation of the process (scene units), `σ`.
    pub sigma: f64,
    /// `(l_x, l_y, l_z)` in scene units; each `> 0`, `+∞` allowed.
    pub lengthscale: DVec3,
}

/// A linear functional of the process: its value or one partial derivative at a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Functional {
    /// `f(p)`.
    Value(DVec3),
    /// `∂f/∂x_i (p)`, `i ∈ {0, 1, 2}`.
    Partial(DVec3, usize),
}

impl Functional {
    /// The point the functional looks at.
    pub fn point(&self) -> DVec3 {
        match *self {
            Functional::Value(p) | Functional::Partial(p, _) => p,
        }
    }
}

impl SeKernel {
    /// Validates `sigma` (finite, `> 0`) and the lengthscales (`> 0`, `+∞` allowed, not NaN).
    pub fn new(sigma: f64, lengthscale: DVec3) -> Result<SeKernel> {
        if !(sigma.is_finite() && sigma > 0.0) {
            return Err(Error::new(ErrorKind::InvalidValue, format!("parameter \"sigma\" must be finite and > 0, got {sigma}")));
        }
        for (name, l) in [("lengthscale_x", lengthscale.x), ("lengthscale_y", lengthscale.y), ("lengthscale_z", lengthscale.z)] {
            if !(l > 0.0) {
                return Err(Error::new(ErrorKind::InvalidValue, format!("parameter \"{name}\" must be > 0 (+inf allowed), got {l}")));
            }
        }
        Ok(SeKernel { sigma, lengthscale })
    }

    /// The kernel of roughness `alpha` (per axis): `l_i = √2 σ / α_i` (seeds/000 Eq. 4);
    /// `α_i = 0` gives `l_i = +∞` (a height field along that axis).
    pub fn from_roughness(sigma: f64, alpha: DVec3) -> Result<SeKernel> {
        for (name, a) in [("alpha_x", alpha.x), ("alpha_y", alpha.y), ("alpha_z", alpha.z)] {
            if !(a.is_finite() && a >= 0.0) {
                return Err(Error::new(ErrorKind::InvalidValue, format!("parameter \"{name}\" must be finite and >= 0, got {a}")));
            }
        }
        let l = |a: f64| if a == 0.0 { f64::INFINITY } else { std::f64::consts::SQRT_2 * sigma / a };
        SeKernel::new(sigma, DVec3::new(l(alpha.x), l(alpha.y), l(alpha.z)))
    }

    /// The roughness `α_i = √2 σ / l_i` (0 for an infinite lengthscale).
    pub fn roughness(&self) -> DVec3 {
        DVec3::new(
            macrofacet::ndf::alpha_from_kernel(self.sigma, self.lengthscale.x),
            macrofacet::ndf::alpha_from_kernel(self.sigma, self.lengthscale.y),
            macrofacet::ndf::alpha_from_kernel(self.sigma, self.lengthscale.z),
        )
    }

    /// `w_i = 1/l_i²` (0 for `l_i = +∞`).
    pub fn inverse_squared_lengths(&self) -> DVec3 {
        DVec3::ONE / (self.lengthscale * self.lengthscale)
    }

    /// `k(p, q)`.
    pub fn value(&self, p: DVec3, q: DVec3) -> f64 {
        let r = p - q;
        let w = self.inverse_squared_lengths();
        self.sigma * self.sigma * (-0.5 * (r * r).dot(w)).exp()
    }

    /// `k(x, x + s d) / k(x, x) = exp(−½ s² Σ d_i² w_i)`: the correlation along a ray.
    pub fn correlation_along(&self, d: DVec3, s: f64) -> f64 {
        (-0.5 * s * s * (d * d).dot(self.inverse_squared_lengths())).exp()
    }

    /// The step `Δt` with `k(x, x + Δt d)/k(x, x) = rho` exactly (`+∞` when the process is
    /// perfectly correlated along `d`, e.g. a vertical ray in a height field).
    pub fn step_for_correlation(&self, d: DVec3, rho: f64) -> f64 {
        let q = (d * d).dot(self.inverse_squared_lengths());
        if q > 0.0 {
            (-2.0 * rho.ln() / q).sqrt()
        } else {
            f64::INFINITY
        }
    }

    /// Prior variance of a functional: `σ²` for a value, `σ² w_i` for `∂_i f`.
    pub fn variance(&self, a: &Functional) -> f64 {
        let s2 = self.sigma * self.sigma;
        match *a {
            Functional::Value(_) => s2,
            Functional::Partial(_, i) => s2 * self.inverse_squared_lengths()[i],
        }
    }

    /// `cov(a, b)` in closed form (table in the module documentation).
    pub fn covariance(&self, a: &Functional, b: &Functional) -> f64 {
        let w = self.inverse_squared_lengths();
        let r = a.point() - b.point();
        let k = self.sigma * self.sigma * (-0.5 * (r * r).dot(w)).exp();
        match (*a, *b) {
            (Functional::Value(_), Functional::Value(_)) => k,
            (Functional::Value(_), Functional::Partial(_, j)) => k * w[j] * r[j],
            (Functional::Partial(_, i), Functional::Value(_)) => -k * w[i] * r[i],
            (Functional::Partial(_, i), Functional::Partial(_, j)) => {
                let delta = if i == j { w[i] } else { 0.0 };
                k * (delta - w[i] * w[j] * r[i] * r[j])
            }
        }
    }
}

impl Covariance for SeKernel {
    type Local = ();

    fn local(&self, _: DVec3, _: bool) -> Result<()> {
        Ok(())
    }
    fn covariance(&self, a: &Functional, _: &(), b: &Functional, _: &()) -> f64 {
        SeKernel::covariance(self, a, b)
    }
    fn variance(&self, a: &Functional, _: &()) -> f64 {
        SeKernel::variance(self, a)
    }
    fn sigma(&self, _: &()) -> f64 {
        self.sigma
    }
    fn region_sigma(&self) -> f64 {
        self.sigma
    }
    fn step_for_correlation(&self, _: &(), d: DVec3, rho: f64) -> f64 {
        SeKernel::step_for_correlation(self, d, rho)
    }
    fn random_partial(&self, _: &(), i: usize) -> bool {
        self.inverse_squared_lengths()[i] > 0.0
    }
    fn params(&self, _: &()) -> LocalParams {
        LocalParams::default()
    }
}
