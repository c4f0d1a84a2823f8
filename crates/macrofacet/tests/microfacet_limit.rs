//! Validation target 6 (reduced form for CI): a macrofacet slab reproduces the microfacet BRDF.
//!
//! Single scattering of a semi-infinite slab of conductor flakes with Gaussian heights equals the
//! analytic microfacet BRDF with Smith's *height-correlated* masking-shadowing,
//! `f1 cos θo = F(wi·h) D(h) / (4 cos θi (1 + Λ(wi) + Λ(wo)))` (seeds/002 §3; Heitz 2014). The
//! slab is infinite, so this holds for any σ: it is the thin-shell limit of seeds/000 Sec. 5.1.
//! Multiple scattering conserves energy (white furnace, tests/slab.rs) and is compared in full
//! with an independent Heitz et al. 2016 random walk by the validation report.

use macrofacet_validation::common;

use common::spherical;
use glam::DVec3;
use macrofacet::fresnel::{conductor_preset, fresnel_conductor_rgb};
use macrofacet::height::HeightProfile;
use macrofacet::ndf::{Beckmann, Ggx, Gtr, GtrLambda, Ltmd, LtmdBase, MicrofacetDistribution, Ndf};
use macrofacet_validation::slab::reflected_density;
use macrofacet_validation::stats::{mean_and_standard_error, Pcg32};
use macrofacet::{MacrofacetMedium, MacrofacetPhase, MicroBsdf, VndfSampling};

fn analytic_single_scattering(ndf: &Ndf, eta: [f64; 3], k: [f64; 3], wi: DVec3, wo: DVec3) -> [f64; 3] {
    let h = (wi + wo).normalize();
    let g2 = 1.0 / (1.0 + ndf.lambda(wi) + ndf.lambda(wo));
    let f = fresnel_conductor_rgb(wi.dot(h), eta, k);
    f.map(|fc| fc * ndf.d(h) * g2 / (4.0 * wi.z))
}

#[test]
fn single_scattering_equals_the_microfacet_brdf() {
    let gold = conductor_preset("Au").unwrap();
    let cases = [
        ("beckmann 0.3", Ndf::Beckmann(Beckmann::new(0.3, 0.3).unwrap())),
        ("beckmann 0.6x0.2", Ndf::Beckmann(Beckmann::new(0.6, 0.2).unwrap())),
        ("ggx 0.5", Ndf::Ggx(Ggx::new(0.5, 0.5).unwrap())),
        // seeds/001: heavier-than-GGX tail, and a skewed lighter one (Fig. 1's transform).
        ("gtr 0.4 γ=1.5", Ndf::Gtr(Gtr::new(0.4, 1.5, GtrLambda::Exact).unwrap())),
        ("gtr 0.3 γ=3 skew", Ndf::Ltmd(Ltmd::new(LtmdBase::Gtr(Gtr::new(0.3, 3.0, GtrLambda::Exact).unwrap()),
            glam::DMat2::from_cols(glam::DVec2::new(1.0, 0.0), glam::DVec2::new(2.0, 1.0))).unwrap())),
    ];
    let pairs = [(spherical(0.0, 0.0), spherical(0.4, 1.0)), (spherical(0.9, 0.0), spherical(0.7, 3.0)), (spherical(1.3, 0.5), spherical(1.1, 0.6))];
    for (i, (name, ndf)) in cases.into_iter().enumerate() {
        // Shell top at 8σ: the flakes a 3σ cut would drop (Φ(-3) = 1.3e-3) would bias the test.
        let medium = MacrofacetMedium {
            height: HeightProfile::new(0.01, 8.0).unwrap(),
            phase: MacrofacetPhase { ndf, micro_bsdf: MicroBsdf::Conductor { eta: gold.eta, k: gold.k, specular_reflectance: [1.0; 3] }, sampling: VndfSampling::Exact },
        };
        for (j, (wi, wo)) in pairs.iter().enumerate() {
            let mut rng = Pcg32::new(7, (i * 10 + j) as u64);
            let n = 100_000;
            let analytic = analytic_single_scattering(&ndf, gold.eta, gold.k, *wi, *wo);
            for (c, expected) in analytic.into_iter().enumerate() {
                let mut rng_c = rng.clone();
                let (mean, se) = mean_and_standard_error((0..n).map(|_| reflected_density(&medium, *wi, *wo, 1, || rng_c.next_f64())[c]));
                // 4.6 standard errors (Šidák over 45 comparisons at overall 1 %).
                assert!((mean - expected).abs() <= 4.6 * se, "{name}, wi={wi}, wo={wo}, channel {c}: slab {mean} ± {se}, microfacet {expected}");
            }
            rng.next_u32();
        }
    }
}
