//! Validation target 6, multiple scattering (reduced form for CI): the macrofacet slab walk
//! against an independent implementation of the microsurface random walk of Heitz, Hanika,
//! d'Eon and Dachsbacher 2016 ("Multiple-scattering microfacet BSDFs with the Smith model",
//! Sec. 5–6; `heitz_walk` of the validation report's reference module, which shares no code with
//! the library): heights sampled by inverting the height CDF `C1` with Smith's `Λ`. Gaussian
//! heights, GGX and Beckmann, gold conductor flakes: the per-channel albedo and the
//! scattering-order histogram must agree.

use macrofacet_validation::common;

use common::spherical;
use common::reference::{heitz_walk, Dist};
use macrofacet::fresnel::conductor_preset;
use macrofacet::height::HeightProfile;
use macrofacet::ndf::{Beckmann, Ggx, Ndf};
use macrofacet_validation::slab::{random_walk, WalkOutcome};
use macrofacet_validation::stats::{mean_and_standard_error, Pcg32};
use macrofacet::{MacrofacetMedium, MacrofacetPhase, MicroBsdf, VndfSampling};

#[test]
fn macrofacet_slab_matches_the_heitz_2016_random_walk() {
    let gold = conductor_preset("Au").unwrap();
    let cases = [
        (Dist::Ggx(0.5), Ndf::Ggx(Ggx::new(0.5, 0.5).unwrap())),
        (Dist::Ggx(1.0), Ndf::Ggx(Ggx::new(1.0, 1.0).unwrap())),
        (Dist::Beckmann(0.7), Ndf::Beckmann(Beckmann::new(0.7, 0.7).unwrap())),
    ];
    for (i, (dist, ndf)) in cases.into_iter().enumerate() {
        let alpha = dist.alpha();
        let medium = MacrofacetMedium {
            height: HeightProfile::new(1.0, 8.0).unwrap(),
            phase: MacrofacetPhase {
                ndf,
                micro_bsdf: MicroBsdf::Conductor { eta: gold.eta, k: gold.k, specular_reflectance: [1.0; 3] },
                sampling: VndfSampling::Exact,
            },
        };
        for (j, wi) in [spherical(0.0, 0.0), spherical(1.2, 0.3)].into_iter().enumerate() {
            let n = 200_000;
            let mut rng = Pcg32::new(2016, (i * 10 + j) as u64);
            let heitz: Vec<([f64; 3], u32)> = (0..n)
                .map(|_| heitz_walk(&dist, gold.eta, gold.k, wi, 10_000, &mut rng))
                .map(|p| (p.energy, p.order))
                .collect();
            let ours: Vec<([f64; 3], u32)> = (0..n)
                .map(|_| match random_walk(&medium, wi, 10_000, || rng.next_f64()) {
                    WalkOutcome::Escaped { weight, scatterings, .. } => (weight, scatterings),
                    _ => ([0.0; 3], 0),
                })
                .collect();
            for c in 0..3 {
                let a = mean_and_standard_error(heitz.iter().map(|x| x.0[c]));
                let b = mean_and_standard_error(ours.iter().map(|x| x.0[c]));
                let se = (a.1 * a.1 + b.1 * b.1).sqrt();
                // 4 standard errors: Šidák over 18 comparisons at overall 1 %.
                assert!((a.0 - b.0).abs() < 4.0 * se, "alpha {alpha}, wi {wi}, channel {c}: Heitz {} ± {}, macrofacet {} ± {}", a.0, a.1, b.0, b.1);
            }
            // The share of light that needs two or more bounces: the multiple-scattering part.
            // Counted with mirror flakes: with gold, the slab walk's Russian roulette ends some
            // paths early (unbiased for the albedo, but not for the order histogram).
            let mut mirror = medium;
            mirror.phase.micro_bsdf = MicroBsdf::Mirror { specular_reflectance: [1.0; 3] };
            let white = ([1e9; 3], [0.0; 3]); // F = 1 to 1e-9
            let heitz: Vec<u32> = (0..n).map(|_| heitz_walk(&dist, white.0, white.1, wi, 10_000, &mut rng).order).collect();
            let ours: Vec<u32> = (0..n)
                .map(|_| match random_walk(&mirror, wi, 10_000, || rng.next_f64()) {
                    WalkOutcome::Escaped { scatterings, .. } => scatterings,
                    other => panic!("mirror flakes lost a path: {other:?}"),
                })
                .collect();
            let multi = |v: &[u32]| v.iter().filter(|&&x| x >= 2).count() as f64 / n as f64;
            let (pa, pb) = (multi(&heitz), multi(&ours));
            let se = (pa * (1.0 - pa) / n as f64 * 2.0).sqrt();
            assert!((pa - pb).abs() < 4.0 * se, "alpha {alpha}, wi {wi}: P(order >= 2): Heitz {pa}, macrofacet {pb}");
            assert!(pa > 0.01, "alpha {alpha}: multiple scattering must matter in this test ({pa})");
        }
    }
}
