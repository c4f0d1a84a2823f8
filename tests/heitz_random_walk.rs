//! Validation target 6, multiple scattering (reduced form for CI): the macrofacet slab walk
//! against an independent implementation of the microsurface random walk of Heitz, Hanika,
//! d'Eon and Dachsbacher 2016 ("Multiple-scattering microfacet BSDFs with the Smith model",
//! Sec. 5–6): heights sampled by inverting the height CDF `C1` with Smith's `Λ`, visible normals
//! by Heitz 2018's hemisphere construction. Gaussian heights, GGX, gold conductor flakes:
//! the per-channel albedo and the scattering-order histogram must agree.

mod common;

use common::spherical;
use glam::DVec3;
use macrofacet::fresnel::{conductor_preset, fresnel_conductor_rgb};
use macrofacet::height::HeightProfile;
use macrofacet::ndf::{Ggx, Ndf};
use macrofacet::slab::{random_walk, WalkOutcome};
use macrofacet::special::{normal_cdf, probit};
use macrofacet::stats::{mean_and_standard_error, Pcg32};
use macrofacet::{MacrofacetMedium, MacrofacetPhase, MicroBsdf, VndfSampling};
use std::f64::consts::PI;

/// GGX Smith Λ for a direction (Heitz's sign convention: for downward rays −1 − Λ(−w)).
fn ggx_lambda(alpha: f64, w: DVec3) -> f64 {
    if w.z > 0.0 {
        let tan2 = (1.0 - w.z * w.z) / (w.z * w.z);
        0.5 * (-1.0 + (1.0 + alpha * alpha * tan2).sqrt())
    } else {
        -1.0 - ggx_lambda(alpha, -w)
    }
}

/// Heitz 2018, "Sampling the GGX distribution of visible normals", Listing 1 (isotropic).
fn ggx_sample_vndf(alpha: f64, v: DVec3, u1: f64, u2: f64) -> DVec3 {
    let vh = DVec3::new(alpha * v.x, alpha * v.y, v.z).normalize();
    let lensq = vh.x * vh.x + vh.y * vh.y;
    let t1 = if lensq > 0.0 { DVec3::new(-vh.y, vh.x, 0.0) / lensq.sqrt() } else { DVec3::X };
    let t2 = vh.cross(t1);
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    DVec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0)).normalize()
}

/// Heitz 2016 `sampleHeight`: the height of the next intersection, or `None` (escaped).
fn sample_height(alpha: f64, wr: DVec3, hr: f64, u: f64) -> Option<f64> {
    if wr.z > 0.9999 {
        return None;
    }
    if wr.z < -0.9999 {
        return Some(probit(u * normal_cdf(hr)));
    }
    if wr.z.abs() < 1e-4 {
        return Some(hr);
    }
    let lambda = ggx_lambda(alpha, wr);
    let g1 = if wr.z > 0.0 { normal_cdf(hr).powf(lambda) } else { 0.0 };
    if u > 1.0 - g1 {
        return None;
    }
    Some(probit(normal_cdf(hr) / (1.0 - u).powf(1.0 / lambda)))
}

/// One microsurface walk; returns the throughput and the number of scattering events.
fn heitz_walk(alpha: f64, eta: [f64; 3], k: [f64; 3], wi: DVec3, rng: &mut Pcg32) -> ([f64; 3], u32) {
    let mut wr = -wi;
    let mut hr = 1.0 + probit(0.999);
    let mut energy = [1.0; 3];
    for order in 0..10_000 {
        match sample_height(alpha, wr, hr, rng.next_f64()) {
            None => return (energy, order),
            Some(h) => hr = h,
        }
        let m = ggx_sample_vndf(alpha, -wr, rng.next_f64(), rng.next_f64());
        let f = fresnel_conductor_rgb((-wr).dot(m), eta, k);
        energy = [0, 1, 2].map(|c| energy[c] * f[c]);
        wr = wr - 2.0 * wr.dot(m) * m;
    }
    ([0.0; 3], 10_000)
}

#[test]
fn macrofacet_slab_matches_the_heitz_2016_random_walk() {
    let gold = conductor_preset("Au").unwrap();
    for (i, alpha) in [0.5, 1.0].into_iter().enumerate() {
        let medium = MacrofacetMedium {
            height: HeightProfile::new(1.0, 8.0).unwrap(),
            phase: MacrofacetPhase {
                ndf: Ndf::Ggx(Ggx::new(alpha, alpha).unwrap()),
                micro_bsdf: MicroBsdf::Conductor { eta: gold.eta, k: gold.k, specular_reflectance: [1.0; 3] },
                sampling: VndfSampling::Exact,
            },
        };
        for (j, wi) in [spherical(0.0, 0.0), spherical(1.2, 0.3)].into_iter().enumerate() {
            let n = 200_000;
            let mut rng = Pcg32::new(2016, (i * 10 + j) as u64);
            let heitz: Vec<([f64; 3], u32)> = (0..n).map(|_| heitz_walk(alpha, gold.eta, gold.k, wi, &mut rng)).collect();
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
                // 4 standard errors: Šidák over 12 comparisons at overall 1 %.
                assert!((a.0 - b.0).abs() < 4.0 * se, "alpha {alpha}, wi {wi}, channel {c}: Heitz {} ± {}, macrofacet {} ± {}", a.0, a.1, b.0, b.1);
            }
            // The share of light that needs two or more bounces: the multiple-scattering part.
            // Counted with mirror flakes: with gold, the slab walk's Russian roulette ends some
            // paths early (unbiased for the albedo, but not for the order histogram).
            let mut mirror = medium;
            mirror.phase.micro_bsdf = MicroBsdf::Mirror { specular_reflectance: [1.0; 3] };
            let white = ([1e9; 3], [0.0; 3]); // F = 1 exactly
            let heitz: Vec<u32> = (0..n).map(|_| heitz_walk(alpha, white.0, white.1, wi, &mut rng).1).collect();
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
