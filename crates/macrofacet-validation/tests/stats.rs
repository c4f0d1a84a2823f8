//! Tests of `macrofacet_validation::stats`: the generator against the PCG32 reference, the special
//! functions against mpmath, and the goodness-of-fit tests on exact and slightly wrong
//! samplers (they must accept the former and reject the latter).
//!
//! Run with `cargo test --release --test stats`.

#![allow(clippy::excessive_precision)] // mpmath reference values are pasted at 17 digits

use core::f64::consts::PI;
use glam::DVec3;
use macrofacet_validation::stats::*;

/// Number of acceptance tests of exact samplers in this file that share one family-wise level.
const N_ACCEPTANCE_TESTS: usize = 13;
/// Family-wise false-rejection level of this file's acceptance tests.
const FAMILY_ALPHA: f64 = 0.01;

fn alpha() -> f64 {
    sidak_alpha(FAMILY_ALPHA, N_ACCEPTANCE_TESTS)
}

fn rel_err(got: f64, want: f64) -> f64 {
    ((got - want) / want).abs()
}

// ------------------------------------------------------------------------------------------
// Pcg32
// ------------------------------------------------------------------------------------------

#[test]
fn pcg32_matches_reference_demo_sequence() {
    // pcg32-global-demo / pcg32_srandom_r(&rng, 42u, 54u): first six outputs.
    let mut rng = Pcg32::new(42, 54);
    let want = [0xa15c02b7u32, 0x7b47f409, 0xba1d3330, 0x83d2f293, 0xbfa4784b, 0xcbed606e];
    for (i, &w) in want.iter().enumerate() {
        let got = rng.next_u32();
        assert_eq!(got, w, "output {i}: got {got:#010x}, want {w:#010x}");
    }
}

#[test]
fn pcg32_is_deterministic_and_streams_differ() {
    let a: Vec<u32> = {
        let mut r = Pcg32::new(7, 3);
        (0..16).map(|_| r.next_u32()).collect()
    };
    let b: Vec<u32> = {
        let mut r = Pcg32::new(7, 3);
        (0..16).map(|_| r.next_u32()).collect()
    };
    let c: Vec<u32> = {
        let mut r = Pcg32::new(7, 4);
        (0..16).map(|_| r.next_u32()).collect()
    };
    assert_eq!(a, b);
    assert_ne!(a, c);
}

#[test]
fn pcg32_floats_are_in_range_and_use_53_bits() {
    // next_f64 is built from two consecutive outputs: high 32 bits then low 32 bits.
    let mut r = Pcg32::new(42, 54);
    let u = r.next_f64();
    let bits = ((0xa15c02b7u64 << 32) | 0x7b47f409) >> 11;
    assert_eq!(u, bits as f64 / 2f64.powi(53));

    let mut r = Pcg32::new(1, 1);
    let mut any_low_bits = false;
    for _ in 0..100_000 {
        let u = r.next_f64();
        assert!((0.0..1.0).contains(&u));
        // A 32-bit float construction would leave the low 21 bits of the mantissa empty.
        any_low_bits |= ((u * 2f64.powi(53)) as u64) & 0x1f_ffff != 0;
        let v = r.next_f64_open();
        assert!(v > 0.0 && v < 1.0);
    }
    assert!(any_low_bits);
}

// ------------------------------------------------------------------------------------------
// Special functions against mpmath
// ------------------------------------------------------------------------------------------

// Reference values from mpmath 1.3.0 at 40 digits:
//   import mpmath as mp; mp.mp.dps = 40
//   q = mp.gammainc(a, x, mp.inf, regularized=True)     # Q(a, x)
//   p = mp.gammainc(a, 0, x, regularized=True)          # P(a, x)
//   chi2_sf(s, k) = mp.gammainc(mp.mpf(k)/2, mp.mpf(s)/2, mp.inf, regularized=True)
//   Q_KS(l) = 2*mp.nsum(lambda j: (-1)**(j-1)*mp.exp(-2*j*j*l*l), [1, mp.inf])
//     (cross-checked against 1 - mp.sqrt(2*mp.pi)/l*mp.nsum(lambda j:
//      mp.exp(-(2*j-1)**2*mp.pi**2/(8*l*l)), [1, mp.inf]) to 1e-30)
//   printed with mp.nstr(v, 17, min_fixed=-1, max_fixed=-1)

const GAMMA_Q_TABLE: [(f64, f64, f64); 25] = [
    (0.5, 0.01, 8.8753708398171511e-1),
    (0.5, 1.0, 1.5729920705028513e-1),
    (0.5, 30.0, 9.4857375710738484e-15),
    (1.0, 0.5, 6.0653065971263342e-1),
    (1.0, 50.0, 1.9287498479639178e-22),
    (1.5, 2.5, 1.7179714429673314e-1),
    (2.5, 1.0, 8.4914503608460964e-1),
    (3.0, 10.0, 2.7693957155115759e-3),
    (5.0, 4.0, 6.2883693517987352e-1),
    (5.0, 6.0, 2.8505650031663122e-1),
    (9.5, 9.0, 5.2243827398626292e-1),
    (10.0, 10.0, 4.5792971447185221e-1),
    (10.0, 30.0, 7.1217508628155771e-6),
    (25.5, 20.0, 8.6687744202400728e-1),
    (25.5, 27.0, 3.604836044989285e-1),
    (50.0, 45.0, 7.5319796559982973e-1),
    (50.0, 100.0, 1.1784500720979422e-8),
    (100.0, 100.0, 4.8670120172085134e-1),
    (100.0, 130.0, 2.7504083673065263e-3),
    (100.0, 70.0, 9.9956962740502011e-1),
    (500.0, 480.0, 8.137180268096754e-1),
    (500.0, 560.0, 4.6931659992947694e-3),
    (1000.0, 1000.0, 4.9579475581978449e-1),
    (1000.0, 1100.0, 1.0593232539299773e-3),
    (2500.0, 2400.0, 9.7834031213463667e-1),
];

const GAMMA_P_TABLE: [(f64, f64, f64); 6] = [
    (0.5, 0.0001, 1.1283415555849617e-2),
    (2.0, 0.01, 4.9667913340265892e-5),
    (10.0, 1.0, 1.1142547833872068e-7),
    (50.0, 20.0, 1.2458926079719379e-8),
    (3.0, 2.0, 3.2332358381693654e-1),
    (100.0, 99.0, 4.7330433039946099e-1),
];

const CHI2_SF_TABLE: [(f64, usize, f64); 13] = [
    (0.5, 1, 4.7950012218695346e-1),
    (3.841458820694124, 1, 5.0000000000000057e-2),
    (10.0, 1, 1.5654022580025497e-3),
    (1.0, 2, 6.0653065971263342e-1),
    (5.99, 2, 5.0036627086586283e-2),
    (20.0, 3, 1.6974243555282643e-4),
    (7.0, 7, 4.2887985755305472e-1),
    (30.0, 10, 8.5664121077530039e-4),
    (100.0, 50, 3.4549313829848639e-5),
    (250.0, 200, 9.3791316688260961e-3),
    (150.0, 200, 9.9664755850181301e-1),
    (400.0, 255, 1.6600025244124518e-8),
    (1200.0, 1000, 1.2255942330622904e-5),
];

const KOLMOGOROV_SF_TABLE: [(f64, f64); 14] = [
    (0.3, 9.9999069419866543e-1),
    (0.5, 9.6394524366487509e-1),
    (0.7, 7.1123519502968925e-1),
    (0.8, 5.4414241157419808e-1),
    (1.0, 2.6999967167735452e-1),
    (1.1, 1.7771819260640118e-1),
    (1.17, 1.2939004218561883e-1),
    (1.19, 1.1774229287977168e-1),
    (1.2258, 9.9048503269937063e-2),
    (1.3581, 4.9999630431667413e-2),
    (1.5, 2.2217962616525129e-2),
    (2.0, 6.7092525577969535e-4),
    (3.0, 3.0459959489425257e-8),
    (4.0, 2.5328331098188351e-14),
];

#[test]
fn gamma_q_matches_mpmath() {
    for &(a, x, want) in &GAMMA_Q_TABLE {
        let got = gamma_q(a, x);
        assert!(rel_err(got, want) < 1e-13, "Q({a}, {x}) = {got:e}, mpmath {want:e}");
        let p = gamma_p(a, x);
        assert!((p + got - 1.0).abs() < 1e-14, "P + Q != 1 at ({a}, {x})");
    }
}

#[test]
fn gamma_p_matches_mpmath() {
    for &(a, x, want) in &GAMMA_P_TABLE {
        let got = gamma_p(a, x);
        assert!(rel_err(got, want) < 1e-12, "P({a}, {x}) = {got:e}, mpmath {want:e}");
    }
}

#[test]
fn gamma_edge_cases() {
    assert_eq!(gamma_q(2.0, 0.0), 1.0);
    assert_eq!(gamma_p(2.0, 0.0), 0.0);
    assert_eq!(gamma_q(2.0, f64::INFINITY), 0.0);
    assert!(gamma_q(0.0, 1.0).is_nan());
    assert!(gamma_q(1.0, -1.0).is_nan());
    assert!(gamma_q(f64::NAN, 1.0).is_nan());
    // Q(1, x) = e^{-x} exactly; Q(1/2, x) = erfc(√x).
    for &x in &[1e-3, 0.3, 1.7, 2.0, 5.0, 40.0, 300.0] {
        assert!(rel_err(gamma_q(1.0, x), (-x).exp()) < 1e-13, "Q(1, {x})");
        assert!(rel_err(gamma_q(0.5, x), libm::erfc(x.sqrt())) < 1e-12, "Q(1/2, {x})");
    }
}

#[test]
fn chi2_sf_matches_mpmath() {
    for &(s, k, want) in &CHI2_SF_TABLE {
        let got = chi2_sf(s, k);
        assert!(rel_err(got, want) < 1e-13, "chi2_sf({s}, {k}) = {got:e}, mpmath {want:e}");
    }
    assert_eq!(chi2_sf(0.0, 5), 1.0);
    assert_eq!(chi2_sf(-1.0, 5), 1.0);
    assert_eq!(chi2_sf(f64::INFINITY, 5), 0.0);
    assert_eq!(chi2_sf(0.0, 0), 1.0);
    assert_eq!(chi2_sf(1.0, 0), 0.0);
    assert!(chi2_sf(f64::NAN, 3).is_nan());
}

#[test]
fn kolmogorov_sf_matches_mpmath() {
    for &(l, want) in &KOLMOGOROV_SF_TABLE {
        let got = kolmogorov_sf(l);
        assert!(rel_err(got, want) < 1e-12, "Q_KS({l}) = {got:e}, mpmath {want:e}");
    }
    assert_eq!(kolmogorov_sf(0.0), 1.0);
    assert_eq!(kolmogorov_sf(-1.0), 1.0);
    assert!(kolmogorov_sf(0.05) <= 1.0);
    assert_eq!(kolmogorov_sf(50.0), 0.0);
}

#[test]
fn sidak_alpha_values() {
    // 1 - 0.99^(1/10) and 1 - (1 - 1e-12)^(1/4) from mpmath.
    assert!(rel_err(sidak_alpha(0.01, 10), 0.0010045287082499489) < 1e-13);
    assert!(rel_err(sidak_alpha(1e-12, 4), 2.5000000000009375e-13) < 1e-12);
    assert_eq!(sidak_alpha(0.05, 1), 0.05);
    assert_eq!(sidak_alpha(0.05, 0), 0.05);
    // Family-wise level is recovered.
    let a = sidak_alpha(0.01, 7);
    assert!(((1.0 - (1.0 - a).powi(7)) - 0.01).abs() < 1e-15);
}

// ------------------------------------------------------------------------------------------
// Samplers used by the goodness-of-fit tests
// ------------------------------------------------------------------------------------------

fn uniform_sphere(r: &mut Pcg32) -> DVec3 {
    let z = 1.0 - 2.0 * r.next_f64();
    let phi = 2.0 * PI * r.next_f64();
    let s = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(s * phi.cos(), s * phi.sin(), z)
}

/// Power-cosine lobe `pdf = (n+1)/(2π) cosⁿθ` on the upper hemisphere around `+z`.
fn power_cosine_lobe(r: &mut Pcg32, n: f64) -> DVec3 {
    let z = r.next_f64_open().powf(1.0 / (n + 1.0));
    let phi = 2.0 * PI * r.next_f64();
    let s = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(s * phi.cos(), s * phi.sin(), z)
}

fn power_cosine_pdf(w: DVec3, n: f64) -> f64 {
    if w.z > 0.0 {
        (n + 1.0) / (2.0 * PI) * w.z.powf(n)
    } else {
        0.0
    }
}

fn cosine_hemisphere(r: &mut Pcg32) -> DVec3 {
    let u1 = r.next_f64();
    let phi = 2.0 * PI * r.next_f64();
    let s = u1.sqrt();
    DVec3::new(s * phi.cos(), s * phi.sin(), (1.0 - u1).max(0.0).sqrt())
}

fn cosine_pdf(w: DVec3) -> f64 {
    w.z.max(0.0) / PI
}

/// Rotate `v` so that `+z` goes to the unit `axis` (axis in the x–z plane).
fn rotate_z_to(v: DVec3, axis: DVec3) -> DVec3 {
    let (s, c) = (axis.x, axis.z);
    DVec3::new(c * v.x + s * v.z, v.y, -s * v.x + c * v.z)
}

fn sphere_config(samples: usize) -> SphereChi2 {
    SphereChi2 { theta_bins: 16, phi_bins: 32, samples, quadrature: 4, min_expected: 5.0 }
}

// ------------------------------------------------------------------------------------------
// Sphere chi-square
// ------------------------------------------------------------------------------------------

#[test]
fn sphere_chi2_accepts_uniform_sphere() {
    let mut rng = Pcg32::new(1, 11);
    let out = sphere_config(500_000).run(|_| 1.0 / (4.0 * PI), |r| Some(uniform_sphere(r)), &mut rng);
    assert!((out.pdf_integral - 1.0).abs() < 1e-12, "{out}");
    assert_eq!(out.dof, 16 * 32 - 1); // the null cell has (near) zero expectation: pooled or dropped
    assert!(out.passes(alpha()), "{out}");
}

#[test]
fn sphere_chi2_accepts_cosine_hemisphere() {
    let mut rng = Pcg32::new(2, 11);
    let out = sphere_config(500_000).run(cosine_pdf, |r| Some(cosine_hemisphere(r)), &mut rng);
    assert!((out.pdf_integral - 1.0).abs() < 1e-9, "{out}");
    assert_eq!(out.zero_pdf_samples, 0);
    assert!(out.passes(alpha()), "{out}");
}

#[test]
fn sphere_chi2_accepts_tilted_power_lobe() {
    // A sharp lobe (cos^20) tilted by 40°: most cells get pooled.
    let axis = DVec3::new(40f64.to_radians().sin(), 0.0, 40f64.to_radians().cos());
    let pdf = |w: DVec3| power_cosine_pdf(rotate_z_to(w, DVec3::new(-axis.x, 0.0, axis.z)), 20.0);
    let mut rng = Pcg32::new(3, 11);
    let out = sphere_config(300_000).run(pdf, |r| Some(rotate_z_to(power_cosine_lobe(r, 20.0), axis)), &mut rng);
    assert!((out.pdf_integral - 1.0).abs() < 1e-4, "{out}");
    assert!(out.dof < 16 * 32 - 1, "expected pooling: {out}");
    assert!(out.passes(alpha()), "{out}");
}

#[test]
fn sphere_chi2_accepts_sub_probability_sampler() {
    // Uniform sphere but "no sample" below the horizon: ∫pdf = 1/2, None has probability 1/2.
    let pdf = |w: DVec3| if w.z > 0.0 { 1.0 / (4.0 * PI) } else { 0.0 };
    let sample = |r: &mut Pcg32| Some(uniform_sphere(r)).filter(|w| w.z > 0.0);
    let mut rng = Pcg32::new(4, 11);
    let out = sphere_config(300_000).run(pdf, sample, &mut rng);
    assert!((out.pdf_integral - 0.5).abs() < 1e-12, "{out}");
    assert!(out.passes(alpha()), "{out}");
}

#[test]
fn sphere_chi2_rejects_wrong_exponent() {
    // Samples from cos^1 tested against the normalised cos^1.1 lobe.
    let mut rng = Pcg32::new(5, 11);
    let out = sphere_config(500_000).run(|w| power_cosine_pdf(w, 1.1), |r| Some(cosine_hemisphere(r)), &mut rng);
    assert!((out.pdf_integral - 1.0).abs() < 1e-6, "{out}");
    assert!(!out.passes(alpha()), "a cos^1 sampler passed as cos^1.1: {out}");
    assert!(out.p_value < 1e-6, "{out}");
}

#[test]
fn sphere_chi2_rejects_tilted_cosine_lobe() {
    // Cosine lobe whose axis is tilted by 0.03 rad, tested against the untilted cosine pdf:
    // some samples leak below the horizon, where the pdf is zero.
    let axis = DVec3::new(0.03f64.sin(), 0.0, 0.03f64.cos());
    let mut rng = Pcg32::new(6, 11);
    let out = sphere_config(500_000).run(cosine_pdf, |r| Some(rotate_z_to(cosine_hemisphere(r), axis)), &mut rng);
    assert!(out.zero_pdf_samples > 0, "{out}");
    assert!(!out.passes(alpha()), "a 0.03 rad tilted lobe passed: {out}");
}

#[test]
fn sphere_chi2_accepts_uniform_hemisphere_cut_across_cells() {
    // Uniform density on the hemisphere around an axis tilted by 0.3 rad: the edge of the
    // support crosses cells; a sample in a sliver of a cell whose quadrature nodes all lie
    // outside the support is not a zero-pdf landing (without the refinement in
    // SphereChi2::run this seed puts one there).
    let axis = DVec3::new(0.3f64.sin(), 0.0, 0.3f64.cos());
    let pdf = |w: DVec3| if w.dot(axis) > 0.0 { 0.5 / PI } else { 0.0 };
    let uniform = |r: &mut Pcg32| {
        let z = r.next_f64();
        let phi = 2.0 * PI * r.next_f64();
        let s = (1.0 - z * z).max(0.0).sqrt();
        rotate_z_to(DVec3::new(s * phi.cos(), s * phi.sin(), z), axis)
    };
    let mut rng = Pcg32::new(6, 13);
    let out = sphere_config(1_000_000).run(pdf, |r| Some(uniform(r)), &mut rng);
    assert_eq!(out.zero_pdf_samples, 0, "{out}");
    assert!(out.passes(alpha()), "{out}");
}

#[test]
fn sphere_chi2_rejects_slightly_tilted_sharp_lobe() {
    // cos^20 lobe at 40° sampled around 40° + 0.01 rad (a twentieth of the lobe width); no
    // sample leaves the support, so only the shape of the histogram can tell.
    let a = 40f64.to_radians();
    let axis = DVec3::new(a.sin(), 0.0, a.cos());
    let tilted = DVec3::new((a + 0.01).sin(), 0.0, (a + 0.01).cos());
    let pdf = |w: DVec3| power_cosine_pdf(rotate_z_to(w, DVec3::new(-axis.x, 0.0, axis.z)), 20.0);
    let mut rng = Pcg32::new(6, 12);
    let out = sphere_config(300_000).run(pdf, |r| Some(rotate_z_to(power_cosine_lobe(r, 20.0), tilted)), &mut rng);
    assert_eq!(out.zero_pdf_samples, 0, "{out}");
    assert!(!out.passes(alpha()), "a 0.01 rad tilted lobe passed: {out}");
}

#[test]
fn sphere_chi2_rejects_wrong_none_rate() {
    // The pdf claims all mass above the horizon is sampled, but the sampler drops z < 0.1.
    let pdf = |w: DVec3| if w.z > 0.0 { 1.0 / (4.0 * PI) } else { 0.0 };
    let sample = |r: &mut Pcg32| Some(uniform_sphere(r)).filter(|w| w.z > 0.1);
    let mut rng = Pcg32::new(7, 11);
    let out = sphere_config(200_000).run(pdf, sample, &mut rng);
    assert!(!out.passes(alpha()), "{out}");
}

#[test]
fn sphere_chi2_flags_samples_where_pdf_is_zero() {
    // One sample in 20 000 leaks below the horizon, where the pdf is zero.
    let mut count = 0u64;
    let sample = |r: &mut Pcg32| {
        count += 1;
        let w = cosine_hemisphere(r);
        Some(if count % 20_000 == 0 { -w } else { w })
    };
    let mut rng = Pcg32::new(8, 11);
    let out = sphere_config(200_000).run(cosine_pdf, sample, &mut rng);
    assert_eq!(out.zero_pdf_samples, 10, "{out}");
    assert_eq!(out.p_value, 0.0);
    assert!(!out.passes(alpha()));
}

#[test]
fn sphere_chi2_counts_invalid_samples() {
    let mut count = 0u64;
    let sample = |r: &mut Pcg32| {
        count += 1;
        let w = uniform_sphere(r);
        match count % 50_000 {
            0 => Some(w * 1.001),
            1 => Some(DVec3::new(f64::NAN, 0.0, 1.0)),
            _ => Some(w),
        }
    };
    let mut rng = Pcg32::new(9, 11);
    let out = sphere_config(100_000).run(|_| 1.0 / (4.0 * PI), sample, &mut rng);
    assert_eq!(out.invalid_samples, 4, "{out}");
    assert!(!out.passes(0.0));
    assert!(format!("{out}").contains("invalid samples: 4"));
}

#[test]
fn sphere_chi2_rejects_pdf_with_wrong_normalisation() {
    // Exact cosine sampler, pdf 2% too large: the null cell has zero expected count and the
    // expected counts sum to 1.02 N.
    let mut rng = Pcg32::new(10, 11);
    let out = sphere_config(500_000).run(|w| 1.02 * cosine_pdf(w), |r| Some(cosine_hemisphere(r)), &mut rng);
    assert!((out.pdf_integral - 1.02).abs() < 1e-6);
    assert!(!out.passes(alpha()), "{out}");
}

#[test]
fn sphere_chi2_p_values_of_exact_sampler_are_uniform() {
    let config = SphereChi2 { theta_bins: 8, phi_bins: 16, samples: 10_000, quadrature: 2, min_expected: 5.0 };
    let p: Vec<f64> = (0..200u64)
        .map(|seed| {
            let mut rng = Pcg32::new(seed, 101);
            config.run(cosine_pdf, |r| Some(cosine_hemisphere(r)), &mut rng).p_value
        })
        .collect();
    let (mean, _) = mean_and_standard_error(p.iter().copied());
    assert!((mean - 0.5).abs() < 0.05, "mean p-value {mean}");
    let low = p.iter().filter(|&&x| x < 0.1).count();
    assert!((5..=40).contains(&low), "{low} of 200 p-values below 0.1");
}

#[test]
fn sphere_chi2_outcome_display() {
    let out = Chi2Outcome {
        statistic: 12.5,
        dof: 9,
        p_value: 0.19,
        invalid_samples: 0,
        zero_pdf_samples: 0,
        pdf_integral: 1.0,
    };
    let s = format!("{out}");
    assert!(s.contains("12.5") && s.contains("9 dof"), "{s}");
    assert!(out.passes(0.01) && !out.passes(0.2));
    assert!(!Chi2Outcome { dof: 0, ..out }.passes(0.01), "zero dof must not pass");
}

// ------------------------------------------------------------------------------------------
// 1-D chi-square
// ------------------------------------------------------------------------------------------

fn exp_cdf(x: f64) -> f64 {
    if x <= 0.0 {
        0.0
    } else {
        -libm::expm1(-x)
    }
}

#[test]
fn chi2_1d_accepts_exact_exponential() {
    let mut rng = Pcg32::new(20, 3);
    let samples: Vec<f64> = (0..200_000).map(|_| -rng.next_f64_open().ln()).collect();
    let edges: Vec<f64> = (0..=40).map(|i| i as f64 * 0.15).collect(); // tail beyond 6 pooled
    let out = chi2_1d(exp_cdf, &samples, &edges);
    assert!(out.passes(alpha()), "{out}");
}

#[test]
fn chi2_1d_rejects_wrong_rate() {
    let mut rng = Pcg32::new(21, 3);
    let samples: Vec<f64> = (0..200_000).map(|_| -rng.next_f64_open().ln() / 1.02).collect();
    let edges: Vec<f64> = (0..=40).map(|i| i as f64 * 0.15).collect();
    let out = chi2_1d(exp_cdf, &samples, &edges);
    assert!(!out.passes(alpha()), "{out}");
}

#[test]
fn chi2_1d_handles_atoms_and_invalid() {
    // Mixed distribution: with probability 0.3 the value 1 (an atom), else uniform on [0, 1).
    let cdf = |x: f64| if x < 0.0 { 0.0 } else if x < 1.0 { 0.7 * x } else { 1.0 };
    let mut rng = Pcg32::new(22, 3);
    let mut samples: Vec<f64> =
        (0..100_000).map(|_| if rng.next_f64() < 0.3 { 1.0 } else { rng.next_f64() }).collect();
    let edges: Vec<f64> = (0..=10).map(|i| i as f64 * 0.1).collect();
    let out = chi2_1d(cdf, &samples, &edges);
    assert!(out.passes(alpha()), "{out}");
    samples[0] = f64::NAN;
    let out = chi2_1d(cdf, &samples, &edges);
    assert_eq!(out.invalid_samples, 1);
    assert!(!out.passes(0.0));
}

#[test]
fn chi2_1d_p_values_with_pooling_are_uniform() {
    // 200 cells, 500 samples: expected 2.5 per cell, so pooling is active.
    let edges: Vec<f64> = (0..=200).map(|i| i as f64 / 200.0).collect();
    let p: Vec<f64> = (0..200u64)
        .map(|seed| {
            let mut rng = Pcg32::new(seed, 202);
            let s: Vec<f64> = (0..500).map(|_| rng.next_f64()).collect();
            let out = chi2_1d(|x| x.clamp(0.0, 1.0), &s, &edges);
            assert!(out.dof >= 90 && out.dof <= 100, "{out}");
            out.p_value
        })
        .collect();
    let (mean, _) = mean_and_standard_error(p.iter().copied());
    assert!((mean - 0.5).abs() < 0.05, "mean p-value {mean}");
}

#[test]
fn chi2_counts_pools_and_tests() {
    let out = chi2_counts(&[48, 52, 0, 1], &[50.0, 50.0, 0.5, 0.5], 5.0);
    assert_eq!(out.dof, 1); // {0.5, 0.5, 50} pooled to one cell, then 50
    assert!((out.pdf_integral - 1.0).abs() < 1e-15);
    assert!(out.passes(0.05));
    let out = chi2_counts(&[70, 30], &[50.0, 50.0], 5.0);
    assert!((out.statistic - 16.0).abs() < 1e-12);
    assert!(!out.passes(0.01));
}

// ------------------------------------------------------------------------------------------
// Kolmogorov–Smirnov
// ------------------------------------------------------------------------------------------

#[test]
fn ks_accepts_exact_uniform() {
    let mut rng = Pcg32::new(30, 5);
    let mut s: Vec<f64> = (0..100_000).map(|_| rng.next_f64()).collect();
    let out = ks_test(&mut s, |x| x.clamp(0.0, 1.0));
    assert!(out.passes(alpha()), "{out}");
}

#[test]
fn ks_accepts_exact_exponential() {
    let mut rng = Pcg32::new(31, 5);
    let mut s: Vec<f64> = (0..100_000).map(|_| -rng.next_f64_open().ln()).collect();
    let out = ks_test(&mut s, exp_cdf);
    assert!(out.passes(alpha()), "{out}");
}

#[test]
fn ks_rejects_biased_samplers() {
    let mut rng = Pcg32::new(32, 5);
    let mut s: Vec<f64> = (0..100_000).map(|_| -rng.next_f64_open().ln() / 1.03).collect();
    let out = ks_test(&mut s, exp_cdf);
    assert!(!out.passes(alpha()), "exponential rate 1.03 passed as rate 1: {out}");

    let mut s: Vec<f64> = (0..100_000).map(|_| rng.next_f64().powf(1.02)).collect();
    let out = ks_test(&mut s, |x| x.clamp(0.0, 1.0));
    assert!(!out.passes(alpha()), "u^1.02 passed as uniform: {out}");
}

/// Exponential truncated at `cut`: the mass beyond is "passed through", mapped to +∞.
fn passed_through_exponential(r: &mut Pcg32, cut: f64) -> f64 {
    let x = -r.next_f64_open().ln();
    if x < cut {
        x
    } else {
        f64::INFINITY
    }
}

fn passed_through_cdf(x: f64) -> f64 {
    if x == f64::INFINITY {
        1.0
    } else {
        exp_cdf(x.min(2.0))
    }
}

#[test]
fn ks_handles_passed_through_atom_at_infinity() {
    let mut rng = Pcg32::new(33, 5);
    let mut s: Vec<f64> = (0..100_000).map(|_| passed_through_exponential(&mut rng, 2.0)).collect();
    assert!(s.iter().filter(|x| x.is_infinite()).count() > 10_000);
    let out = ks_test(&mut s, passed_through_cdf);
    assert!(out.passes(alpha()), "{out}");
    // The statistic would be ≥ e^-2 ≈ 0.135 if the left limit at +∞ were ignored.
    assert!(out.statistic < 0.01, "{out}");

    // Wrong atom mass (cut at 2.1 instead of 2).
    let mut s: Vec<f64> = (0..100_000).map(|_| passed_through_exponential(&mut rng, 2.1)).collect();
    let out = ks_test(&mut s, passed_through_cdf);
    assert!(!out.passes(alpha()), "{out}");
}

#[test]
fn ks_handles_interior_atom() {
    // With probability 0.25 exactly 0.5, else uniform.
    let cdf = |x: f64| 0.75 * x.clamp(0.0, 1.0) + if x >= 0.5 { 0.25 } else { 0.0 };
    let mut rng = Pcg32::new(34, 5);
    let mut s: Vec<f64> =
        (0..50_000).map(|_| if rng.next_f64() < 0.25 { 0.5 } else { rng.next_f64() }).collect();
    let out = ks_test(&mut s, cdf);
    assert!(out.statistic < 0.02, "{out}");
    assert!(out.p_value > 1e-3, "{out}");
}

#[test]
fn ks_statistic_exact_small_case_and_failures() {
    // Samples {0.1, 0.5, 0.9} against U(0,1): D = max(1/3-0.1, 2/3-0.5, 1-0.9, 0.1, 0.5-1/3, 0.9-2/3) = 0.2333…
    let mut s = [0.9, 0.1, 0.5];
    let out = ks_test(&mut s, |x| x);
    assert!((out.statistic - (0.9 - 2.0 / 3.0)).abs() < 1e-15, "{out}");
    assert_eq!(s, [0.1, 0.5, 0.9]);
    assert!(!ks_test(&mut [], |x| x).passes(0.0));
    assert!(!ks_test(&mut [0.3, f64::NAN], |x| x).passes(0.0));
}

#[test]
fn ks_p_values_of_exact_samplers_are_uniform() {
    for (name, stream) in [("uniform", 303u64), ("exponential", 304)] {
        let p: Vec<f64> = (0..200u64)
            .map(|seed| {
                let mut rng = Pcg32::new(seed, stream);
                if name == "uniform" {
                    let mut s: Vec<f64> = (0..1000).map(|_| rng.next_f64()).collect();
                    ks_test(&mut s, |x| x.clamp(0.0, 1.0)).p_value
                } else {
                    let mut s: Vec<f64> = (0..1000).map(|_| -rng.next_f64_open().ln()).collect();
                    ks_test(&mut s, exp_cdf).p_value
                }
            })
            .collect();
        let (mean, _) = mean_and_standard_error(p.iter().copied());
        assert!((mean - 0.5).abs() < 0.05, "{name}: mean p-value {mean}");
    }
}

// ------------------------------------------------------------------------------------------
// Mean and standard error
// ------------------------------------------------------------------------------------------

#[test]
fn mean_and_standard_error_values() {
    let (m, se) = mean_and_standard_error([1.0, 2.0, 3.0, 4.0].into_iter());
    assert!((m - 2.5).abs() < 1e-15);
    assert!((se - (5.0f64 / 12.0).sqrt()).abs() < 1e-15); // s² = 5/3, se = √(s²/4)
    // Large offset: naive Σx² would lose all digits.
    let (m, se) = mean_and_standard_error([1.0, 2.0, 3.0, 4.0].iter().map(|x| 1e9 + x));
    assert!((m - (1e9 + 2.5)).abs() < 1e-6);
    assert!((se - (5.0f64 / 12.0).sqrt()).abs() < 1e-9);
    let (m, se) = mean_and_standard_error(core::iter::empty());
    assert!(m.is_nan() && se.is_nan());
    let (m, se) = mean_and_standard_error(core::iter::once(3.0));
    assert_eq!(m, 3.0);
    assert!(se.is_nan());
}

#[test]
fn mean_and_standard_error_furnace_style() {
    // E[U] = 1/2 within 4 standard errors; and a biased estimator is caught.
    let mut rng = Pcg32::new(40, 1);
    let (m, se) = mean_and_standard_error((0..100_000).map(|_| rng.next_f64()));
    assert!((m - 0.5).abs() < 4.0 * se, "{m} ± {se}");
    assert!((se - (1.0f64 / 12.0 / 1e5).sqrt()).abs() < 2e-5);
    let (m, se) = mean_and_standard_error((0..100_000).map(|_| 1.01 * rng.next_f64()));
    assert!((m - 0.5).abs() > 4.0 * se, "{m} ± {se}");
}
