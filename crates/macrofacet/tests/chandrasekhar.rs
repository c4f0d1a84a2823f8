//! Validation target 8 (reduced form for CI): the isotropic-scattering limit.
//!
//! Mirror flakes with an isotropic normal distribution scatter isotropically (seeds/002 §4.2), and
//! a generalized macrofacet with `alpha_x = alpha_y = alpha_z = α → ∞` has an isotropic NDF (the
//! gradient's mean `e_z` becomes negligible) and a direction-independent projected area (relative
//! anisotropy `O(1/α)`, 1e-4 at α = 1e4). A semi-infinite slab of such flakes with albedo `a` must
//! reproduce Chandrasekhar's results: single scattering seeds/002 Eq. 25,
//! `f1 = a / (4π (μi + μo))`, and all orders seeds/002 Eq. 30, `fr = a H(μi) H(μo) / (4π (μi + μo))`, with
//! the H-function of seeds/002 Eq. 31, `H(μ) = exp(-(μ/π) ∫_0^{π/2} ln(1 - a t cot t) / (cos² t + μ² sin² t) dt)`.

use macrofacet_validation::common;

use common::reference::h_function;
use common::{gauss_legendre, spherical};
use glam::DVec3;
use macrofacet::height::HeightProfile;
use macrofacet::ndf::{Gpss, Ndf};
use macrofacet_validation::slab::reflected_density;
use macrofacet_validation::stats::{mean_and_standard_error, Pcg32};
use macrofacet::{MacrofacetMedium, MacrofacetPhase, MicroBsdf, VndfSampling};
use std::f64::consts::PI;

fn isotropic_slab(albedo: f64) -> MacrofacetMedium {
    let alpha = 1e4;
    MacrofacetMedium {
        height: HeightProfile::new(1.0, 8.0).unwrap(),
        phase: MacrofacetPhase {
            ndf: Ndf::Gpss(Gpss::new(alpha, alpha, alpha).unwrap()),
            micro_bsdf: MicroBsdf::Mirror { specular_reflectance: [albedo; 3] },
            sampling: VndfSampling::Exact,
        },
    }
}

#[test]
fn h_function_matches_published_values() {
    // Conservative case a = 1 (log singularity at t = 0): H(1) = 2.9078 as tabulated by
    // Chandrasekhar (1960); H(0.5) = 2.012779 and H(1) = 2.907811 from seeds/002 Eq. 31 evaluated with
    // mpmath at 60 digits.
    assert!((h_function(0.5, 1.0) - 2.012779).abs() < 1e-4, "H(0.5) = {}", h_function(0.5, 1.0));
    assert!((h_function(1.0, 1.0) - 2.907811).abs() < 1e-4, "H(1) = {}", h_function(1.0, 1.0));
    // Its zeroth moment: ∫_0^1 H dμ = 2 (1 - sqrt(1 - a)) / a.
    for a in [0.5, 0.9] {
        let gl = gauss_legendre(32);
        let moment: f64 = gl.iter().map(|&(x, w)| 0.5 * w * h_function(0.5 * (x + 1.0), a)).sum();
        let expected = 2.0 * (1.0 - (1.0 - a).sqrt()) / a;
        assert!((moment - expected).abs() < 1e-6, "a = {a}: ∫ H = {moment}, expected {expected}");
    }
}

fn check(orders: u32, formula: impl Fn(f64, f64) -> f64, label: &str) {
    let albedo = 0.8;
    let medium = isotropic_slab(albedo);
    let pairs = [(spherical(0.0, 0.0), spherical(0.5, 1.0)), (spherical(1.0, 0.0), spherical(0.3, 2.5)), (spherical(1.3, 0.0), spherical(1.2, 0.1))];
    for (j, (wi, wo)) in pairs.iter().enumerate() {
        let (mi, mo) = (wi.z, wo.z);
        let mut rng = Pcg32::new(11, j as u64);
        let n = 100_000;
        let (mean, se) = mean_and_standard_error((0..n).map(|_| reflected_density(&medium, *wi, *wo, orders, || rng.next_f64())[0] / mo));
        let expected = formula(mi, mo);
        // 4 standard errors (Šidák over 6 comparisons at 1 %) plus the O(1/α) model error.
        assert!((mean - expected).abs() <= 4.0 * se + 1e-3 * expected, "{label}, μi={mi:.3}, μo={mo:.3}: slab {mean} ± {se}, Chandrasekhar {expected}");
    }
    let _ = DVec3::Z;
}

#[test]
fn single_scattering_matches_chandrasekhar_eq25() {
    check(1, |mi, mo| 0.8 / (4.0 * PI * (mi + mo)), "seeds/002 Eq. 25");
}

#[test]
fn all_orders_match_chandrasekhar_eq30() {
    check(10_000, |mi, mo| 0.8 * h_function(mi, 0.8) * h_function(mo, 0.8) / (4.0 * PI * (mi + mo)), "seeds/002 Eq. 30");
}
