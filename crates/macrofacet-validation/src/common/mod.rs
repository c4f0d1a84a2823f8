//! Quadrature shared by the integration tests.
#![allow(dead_code)]

use glam::DVec3;
use std::f64::consts::PI;

/// The independent reference formulas of the validation report (Gauss–Legendre quadrature, the
/// Heitz 2016 random walk, Chandrasekhar's H-function, ...), shared so that each exists once.
pub use crate::reference;

pub use reference::gauss_legendre;

pub mod meshes;
pub mod planar;

/// `∫_{S²} f(ω) dω` with Gauss–Legendre panels in θ graded toward both poles (where peaked NDFs
/// concentrate) and in φ. `panels` per hemisphere in θ, `n_phi` panels in φ, 8 nodes each.
pub fn sphere_integral(f: impl Fn(DVec3) -> f64, panels: usize, n_phi: usize) -> f64 {
    let gl = gauss_legendre(8);
    // θ panel edges: quadratic grading from each pole to the equator.
    let mut edges = Vec::new();
    for i in 0..=panels {
        edges.push(0.5 * PI * (i as f64 / panels as f64).powi(2));
    }
    for i in (0..panels).rev() {
        edges.push(PI - 0.5 * PI * (i as f64 / panels as f64).powi(2));
    }
    let mut total = 0.0;
    for w in edges.windows(2) {
        let (t0, t1) = (w[0], w[1]);
        for &(xt, wt) in &gl {
            let theta = 0.5 * (t0 + t1) + 0.5 * (t1 - t0) * xt;
            let (st, ct) = theta.sin_cos();
            let jt = 0.5 * (t1 - t0) * wt * st;
            for j in 0..n_phi {
                let (p0, p1) = (2.0 * PI * j as f64 / n_phi as f64, 2.0 * PI * (j + 1) as f64 / n_phi as f64);
                for &(xp, wp) in &gl {
                    let phi = 0.5 * (p0 + p1) + 0.5 * (p1 - p0) * xp;
                    let w = DVec3::new(st * phi.cos(), st * phi.sin(), ct);
                    total += jt * 0.5 * (p1 - p0) * wp * f(w);
                }
            }
        }
    }
    total
}

/// A unit vector from spherical angles (local frame, normal = +z).
pub fn spherical(theta: f64, phi: f64) -> DVec3 {
    let (st, ct) = theta.sin_cos();
    DVec3::new(st * phi.cos(), st * phi.sin(), ct)
}

/// The frame in which to bin a visible-normal density seen from `wi` for a chi-square test.
/// The vNDF vanishes on the great circle `wi·m = 0`, with a kink; binning around the pole `wi`
/// puts that circle on a bin edge. GGX keeps the standard frame instead: its `D` jumps at
/// `m_z = 0`, which is a bin edge there (Beckmann and the generalized NDF are smooth at `m_z = 0`).
pub fn chi2_frame(ndf: &macrofacet::ndf::Ndf, wi: DVec3) -> macrofacet::frame::Frame {
    match ndf {
        // GTR (D(horizon) = c of seeds/001 Eq. 32) and transformed GGX/GTR jump there too.
        macrofacet::ndf::Ndf::Ggx(_) | macrofacet::ndf::Ndf::Gtr(_) | macrofacet::ndf::Ndf::Ltmd(_) => macrofacet::frame::Frame::identity(),
        _ => macrofacet::frame::Frame::from_normal_tangent(wi, DVec3::X).unwrap(),
    }
}
