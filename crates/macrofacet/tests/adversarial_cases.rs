//! Regression tests for the wrong answers that adversarial testing found behind `MF_OK`
//! (issue 9), each built from the exact case of the issue, at the level of the safe core. The
//! same cases through the C ABI are in `tests/ffi_abi.rs`; item 2 (segments above the shell) is
//! in `tests/edge_cases_medium.rs`.

use macrofacet_validation::common;

use common::{sphere_integral, spherical};
use glam::DVec3;
use macrofacet::field::Constant;
use macrofacet::frame::Frame;
use macrofacet_gpis::{GpisSurface, MeanSdf, Plane, StartState, Trace};
use macrofacet::ndf::{Beckmann, BeckmannUniformMixture, Gpss, MicrofacetDistribution, Ndf};
use macrofacet_gpis::gpis_from_params;
use macrofacet_validation::stats::Pcg32;
use macrofacet::{medium_from_params, MacrofacetPhase, MicroBsdf, ParamSet, VndfSampling, PHASE_SAMPLE_DIMENSIONS};
use std::cell::{Cell, RefCell};

fn u5(rng: &mut Pcg32) -> [f64; PHASE_SAMPLE_DIMENSIONS] {
    std::array::from_fn(|_| rng.next_f64())
}

/// A uniform direction on the sphere (or on the lower hemisphere when `below`).
fn direction(rng: &mut Pcg32, below: bool) -> DVec3 {
    let z = if below { -rng.next_f64() } else { 1.0 - 2.0 * rng.next_f64() };
    let phi = 2.0 * std::f64::consts::PI * rng.next_f64();
    let r = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

fn relative(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs())
}

/// Every sample: finite unit `wo`, `pdf > 0` equal to `pdf(wi, wo)` bit for bit, finite weight
/// equal to `eval / pdf` (relative `tol`). Returns how many samples were valid.
fn check_samples(phase: &MacrofacetPhase, wis: impl Iterator<Item = DVec3>, rng: &mut Pcg32, tol: f64, what: &str) -> usize {
    let mut valid = 0;
    for wi in wis {
        let Some(s) = phase.sample(wi, u5(rng)) else { continue };
        valid += 1;
        assert!((s.wo.length() - 1.0).abs() < 1e-14, "{what}, wi {wi}: |wo| = {}", s.wo.length());
        assert!(s.pdf > 0.0 && s.pdf.is_finite(), "{what}, wi {wi}: {s:?}");
        assert_eq!(s.pdf.to_bits(), phase.pdf(wi, s.wo).to_bits(), "{what}, wi {wi}: sampled pdf vs pdf()");
        let eval = phase.eval(wi, s.wo);
        for c in 0..3 {
            assert!(s.weight[c].is_finite(), "{what}, wi {wi}: {s:?}");
            assert!(relative(s.weight[c], eval[c] / s.pdf) <= tol || s.weight[c] == eval[c] / s.pdf, "{what}, wi {wi}: weight {s:?}, eval {eval:?}");
        }
    }
    valid
}

/// Item 1: `vndf_sampling = mixture`, gpss α = 0.3 and 1e-6, α_z = 0, `wi = (0.79, 0, -0.60)`
/// and other directions below the mean surface: no valid sample may carry a NaN weight. (At
/// 1e-6 nothing is visible from below in `f64`: the mixture's uniform half used to return
/// normals of `D_wi = 0/0`.)
#[test]
fn item1_mixture_samples_from_below_have_finite_weights() {
    let mut rng = Pcg32::new(9, 1);
    for alpha in [0.3, 1e-6] {
        let ndf = Gpss::new(alpha, alpha, 0.0).unwrap();
        let mixture = BeckmannUniformMixture::new(ndf, 0.5).unwrap();
        let phase = MacrofacetPhase { ndf: Ndf::Gpss(ndf), micro_bsdf: MicroBsdf::Mirror { specular_reflectance: [1.0; 3] }, sampling: VndfSampling::Mixture(mixture) };
        let issue_wi = DVec3::new(0.79, 0.0, -0.60).normalize();
        let fixed = check_samples(&phase, std::iter::repeat_n(issue_wi, 50_000), &mut rng, 1e-12, "issue wi");
        let wis: Vec<DVec3> = (0..150_000).map(|_| direction(&mut rng, true)).collect();
        let random = check_samples(&phase, wis.into_iter(), &mut rng, 1e-12, "random wi below");
        if alpha == 0.3 {
            assert!(fixed > 40_000 && random > 100_000, "alpha 0.3: {fixed} and {random} valid samples");
        } else {
            assert_eq!(fixed, 0, "alpha 1e-6: no flake is visible from below");
        }
    }
}

/// Item 3: Beckmann and gpss with α_z = 0, any α: `eval` and `pdf` at `wi = (0, 1, 0)`,
/// `wo = (1, 0, z)`, `0 < z ≤ 1e-100` (the half vector grazes the horizon, where `D` was
/// `0/0`).
#[test]
fn item3_grazing_half_vectors_give_zero_not_nan() {
    for alpha in [1e-6, 0.3, 1.0, 1e6] {
        for ndf in [Ndf::Beckmann(Beckmann::new(alpha, alpha).unwrap()), Ndf::Gpss(Gpss::new(alpha, alpha, 0.0).unwrap())] {
            let phase = MacrofacetPhase { ndf, micro_bsdf: MicroBsdf::Mirror { specular_reflectance: [1.0; 3] }, sampling: VndfSampling::Exact };
            let wi = DVec3::Y;
            for z in [1e-80, 1e-100, 1e-160, 1e-200, 1e-300, 5e-324] {
                let wo = DVec3::new(1.0, 0.0, z);
                let (value, pdf) = (phase.eval(wi, wo), phase.pdf(wi, wo));
                assert!(value.iter().all(|v| *v >= 0.0 && v.is_finite()) && pdf >= 0.0 && pdf.is_finite(), "{ndf:?}, z = {z}: eval {value:?}, pdf {pdf}");
                let m = (wi + wo).normalize();
                assert!(ndf.d(m).is_finite(), "{ndf:?}: D({m}) = {}", ndf.d(m));
            }
        }
    }
    // The limit, not a cut-off: D decays continuously to 0 toward the horizon.
    let beckmann = Beckmann::new(0.3, 0.3).unwrap();
    let mut previous = f64::INFINITY;
    for z in [1e-1, 1e-2, 1e-40, 1e-80, 1e-100, 1e-300] {
        let d = beckmann.d(DVec3::new(1.0, 1.0, z).normalize());
        assert!(d <= previous, "D must decrease toward the horizon: {d} after {previous}");
        previous = d;
    }
    assert_eq!(previous, 0.0);
}

/// Item 4: diffuse flakes, Beckmann α = 1000: a valid sample must have `pdf > 0` (4 in 200 000
/// had 0: the sampler drew from the exact vNDF while the pdf is a 256-point rule). Also a grid
/// of extreme random numbers.
#[test]
fn item4_diffuse_samples_have_positive_pdf() {
    let mut params = ParamSet::new();
    params.set_float("sigma", 1.0).set_float("alpha", 1000.0).set_string("distribution", "beckmann").set_string("micro_bsdf", "diffuse");
    let phase = medium_from_params(&params).unwrap().phase;
    let mut rng = Pcg32::new(3, 4);
    let mut valid = 0;
    let edges = [0.0, 1e-300, 0.5, 1.0 - 1e-16];
    let grid = (0..4usize.pow(5)).map(|i| std::array::from_fn(|k| edges[(i >> (2 * k)) & 3]));
    let wis: Vec<DVec3> = (0..200_000).map(|_| direction(&mut rng, false)).collect();
    for (n, wi) in wis.into_iter().enumerate() {
        let u = if n < 4usize.pow(5) { grid.clone().nth(n).unwrap() } else { u5(&mut rng) };
        if let Some(s) = phase.sample(wi, u) {
            valid += 1;
            assert!(s.pdf > 0.0 && s.pdf.is_finite() && s.weight == [0.5; 3], "wi {wi}, u {u:?}: {s:?}");
        }
    }
    assert!(valid > 150_000, "{valid} valid samples");
}

/// The diffuse sampler draws exactly the density that `pdf` evaluates: the sampled mean of
/// `wo.z` and `wo.x` equal their integrals against `pdf` within 4 standard errors.
#[test]
fn diffuse_sampling_density_is_the_evaluated_pdf() {
    let phase = MacrofacetPhase {
        ndf: Ndf::Gpss(Gpss::new(0.7, 0.4, 0.5).unwrap()),
        micro_bsdf: MicroBsdf::Diffuse { reflectance: [0.5; 3] },
        sampling: VndfSampling::Exact,
    };
    let mut rng = Pcg32::new(21, 2);
    for wi in [spherical(0.3, 0.2), spherical(2.4, -1.0)] {
        let n = 20_000;
        let samples: Vec<DVec3> = (0..n).filter_map(|_| phase.sample(wi, u5(&mut rng))).map(|s| s.wo).collect();
        // ∫ pdf, then ∫ pdf wo.z and ∫ pdf wo.x replaying the pdf at the same nodes (in order).
        let cache = RefCell::new(Vec::new());
        let total = sphere_integral(
            |wo| {
                let p = phase.pdf(wi, wo);
                cache.borrow_mut().push(p);
                p
            },
            12,
            12,
        );
        let integral_of = |h: &dyn Fn(DVec3) -> f64| {
            let node = Cell::new(0);
            sphere_integral(
                |wo| {
                    node.set(node.get() + 1);
                    cache.borrow()[node.get() - 1] * h(wo)
                },
                12,
                12,
            )
        };
        assert!(relative(total, samples.len() as f64 / n as f64) < 0.01, "wi {wi}: ∫ pdf = {total}, valid fraction {}", samples.len() as f64 / n as f64);
        for (axis, h) in [("z", &(|w: DVec3| w.z) as &dyn Fn(DVec3) -> f64), ("x", &|w: DVec3| w.x)] {
            let mean = samples.iter().map(|w| h(*w)).sum::<f64>() / n as f64;
            let second = samples.iter().map(|w| h(*w).powi(2)).sum::<f64>() / n as f64;
            let se = ((second - mean * mean) / n as f64).sqrt();
            let expected = integral_of(h);
            assert!((mean - expected).abs() < 4.0 * se + 1e-4, "wi {wi}, E[wo.{axis}]: sampled {mean} ± {se}, ∫ pdf = {expected}");
        }
    }
}

/// Item 5: a frame normal of length ~1e-159 (and other extreme lengths) gives an orthonormal
/// frame, so that world directions stay unit length (0.9999990 before).
#[test]
fn item5_extreme_normal_lengths_give_orthonormal_frames() {
    let tangent = DVec3::new(1.0, 0.3, -0.2);
    for scale in [1e-159, 1e-300, 1e-30, 1.0, 1e200, 1e300, 5e-324] {
        for dir in [DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.3, -0.2, 0.7), DVec3::new(1.0, 2.0, 3.0)] {
            let normal = dir * scale;
            if normal == DVec3::ZERO {
                continue;
            }
            let f = Frame::from_normal_tangent(normal, tangent * scale).unwrap();
            for (name, v) in [("s", f.s), ("t", f.t), ("n", f.n)] {
                assert!((v.length() - 1.0).abs() < 1e-15, "scale {scale}, {dir}: |{name}| = {}", v.length());
            }
            assert!(f.s.dot(f.t).abs() < 1e-15 && f.s.dot(f.n).abs() < 1e-15 && f.t.dot(f.n).abs() < 1e-15, "scale {scale}: {f:?}");
            // (At 5e-324 the input itself has lost its direction to subnormal rounding.)
            assert!(scale < 1e-300 || (f.n - dir.normalize()).length() < 1e-15, "scale {scale}: n = {} for {dir}", f.n);
        }
    }
}

/// A host's mean surface that counts its calls and answers NaN from call `nan_after` on.
struct CountingMean {
    plane: Plane,
    calls: Cell<usize>,
    nan_after: usize,
}

impl CountingMean {
    fn step(&self) -> bool {
        self.calls.set(self.calls.get() + 1);
        self.calls.get() > self.nan_after
    }
}

impl MeanSdf for CountingMean {
    fn value(&self, p: DVec3) -> f64 {
        if self.step() { f64::NAN } else { self.plane.value(p) }
    }
    fn gradient(&self, p: DVec3) -> DVec3 {
        if self.step() { DVec3::NAN } else { self.plane.gradient(p) }
    }
}

fn gpis(memory: &str) -> GpisSurface {
    let mut params = ParamSet::new();
    params.set_float("sigma", 1.0).set_float("alpha", 0.5).set_string("memory", memory);
    gpis_from_params(&params).unwrap()
}

/// Item 6: an on-surface start whose ray points into the remembered surface (`d·∇f < 0`,
/// Renewal+) reported a hit at `t = 0` every time; departures under Renewal did so 7 % of the
/// time. The crossing must lie at `0 < t`.
#[test]
fn item6_on_surface_starts_never_report_t_zero() {
    let plane = Plane { height: 0.0 };
    let g = gpis("renewal_plus");
    let d = DVec3::new(0.6, 0.0, -0.8);
    for seed in 0..1000u64 {
        let mut rng = Pcg32::new(seed, 6);
        let start = StartState::OnSurface { gradient: Some(DVec3::new(0.1, -0.2, 1.0)) };
        match g.trace(&plane, &Constant, DVec3::ZERO, d, f64::INFINITY, &start, &mut || rng.next_f64()).unwrap() {
            Trace::Hit(c) => assert!(c.t > 0.0 && c.t < 1e-2, "seed {seed}: t = {}", c.t),
            other => panic!("seed {seed}: a ray into the surface must hit it, got {other:?}"),
        }
    }
    // Renewal forgets the slope: departures that re-enter at once are placed at 0 < t.
    let g = gpis("renewal");
    let (mut hits, mut immediate) = (0, 0);
    for seed in 0..3000u64 {
        let mut rng = Pcg32::new(seed, 7);
        let d = direction(&mut rng, false) * DVec3::new(1.0, 1.0, 0.0) + DVec3::new(0.0, 0.0, 0.3);
        let start = StartState::OnSurface { gradient: None };
        if let Trace::Hit(c) = g.trace(&plane, &Constant, DVec3::ZERO, d.normalize(), f64::INFINITY, &start, &mut || rng.next_f64()).unwrap() {
            hits += 1;
            assert!(c.t > 0.0 && c.point.is_finite() && c.normal.is_finite(), "seed {seed}: {c:?}");
            immediate += usize::from(c.t < 1e-3);
        }
    }
    assert!(immediate > 50 && hits > immediate, "{hits} re-hits, {immediate} at once: the case must be exercised");
}

/// Item 7: gpss α = 1e-6, α_z = 1e4 — the sampled pdf differed from `pdf` by up to 1.2 %: the
/// sample was evaluated at its normal, `pdf` at the recomputed half vector, 1e-16 apart on a
/// lobe 1e-10 rad wide. Now both are one computation.
#[test]
fn item7_sampled_pdf_is_pdf_at_extreme_anisotropy() {
    let mut params = ParamSet::new();
    params.set_float("sigma", 1.0).set_float("alpha", 1e-6).set_float("alpha_z", 1e4);
    let medium = medium_from_params(&params).unwrap();
    let mut rng = Pcg32::new(7, 8);
    let wis: Vec<DVec3> = (0..100_000).map(|_| direction(&mut rng, false)).collect();
    let valid = check_samples(&medium.phase, wis.into_iter(), &mut rng, 1e-12, "gpss 1e-6 / 1e4");
    assert!(valid > 90_000, "{valid} valid samples");
}

fn medium_error(pairs: &[(&str, f64)]) -> String {
    let mut params = ParamSet::new();
    for (name, value) in pairs {
        params.set_float(name, *value);
    }
    let medium = medium_from_params(&params).err();
    let gpis = gpis_from_params(&params).err();
    let (Some(m), Some(g)) = (medium, gpis) else { panic!("{pairs:?} must be refused by the medium and by gpis") };
    assert!(g.message.contains(&m.message[..m.message.find(" = ").unwrap()]), "{pairs:?}: {} / {}", m.message, g.message);
    m.message
}

/// Item 8: σ = 1e308 was accepted (shell top = inf). Parameters whose derived quantities leave
/// the range of `f64` are refused, naming the parameter and the reason.
#[test]
fn item8_parameters_with_overflowing_derived_quantities_are_refused() {
    let cases: [(&[(&str, f64)], &str); 9] = [
        (&[("sigma", 1e308), ("alpha", 0.3)], "\"sigma\" = 1e308"),
        (&[("sigma", 1e-60), ("alpha", 0.3)], "\"sigma\" = 1e-60"),
        (&[("variance", 1e300), ("alpha", 0.3)], "\"variance\""),
        (&[("sigma", 1.0), ("alpha", 0.3), ("shell_extent", 1e300)], "\"shell_extent\""),
        (&[("sigma", 1e-50), ("alpha", 0.3), ("shell_extent", 1e-300)], "\"shell_extent\""),
        (&[("sigma", 1.0), ("alpha", 1e-7)], "\"alpha\""),
        (&[("sigma", 1.0), ("alpha", 1e7)], "\"alpha\""),
        (&[("sigma", 1.0), ("alpha_u", 0.3), ("alpha_v", 0.3), ("alpha_z", 1e-20)], "\"alpha_z\""),
        (&[("sigma", 1.0), ("lengthscale", 1e-300)], "\"lengthscale\""),
    ];
    for (pairs, named) in cases {
        let message = medium_error(pairs);
        assert!(message.contains(named) && message.contains("outside"), "{pairs:?}: {message}");
    }
    // A conductor index whose Fresnel squares overflow (the fuzz target's first NaN).
    let mut params = ParamSet::new();
    params.set_float("sigma", 3.0).set_float("lengthscale", 0.1175).set_rgb("eta", [3.0, f64::MAX, 10.0]).set_rgb("k", [31.6; 3]);
    let message = medium_from_params(&params).unwrap_err().message;
    assert!(message.contains("\"eta\" (channel 1)"), "{message}");
    for (eta, k) in [(1e6, 1e6), (1e-6, 0.0), (1e-6, 1e6), (1e6, 0.0)] {
        for cos in [0.0, 1e-300, 0.3, 1.0] {
            let f = macrofacet::fresnel::fresnel_conductor(cos, eta, k);
            assert!((0.0..=1.0).contains(&f), "Fresnel({cos}, {eta}, {k}) = {f}");
        }
    }
    // A gpis band too narrow to be a ground truth.
    let message = medium_gpis_error(&[("sigma", 1.0), ("alpha", 0.3), ("shell_extent", 2.0)]);
    assert!(message.contains("gpis band") && message.contains("outside"), "{message}");
    // The edges of the domain are accepted and give finite answers.
    for pairs in [
        [("sigma", 1e50), ("alpha", 1e6), ("shell_extent", 40.0)],
        [("sigma", 1e-50), ("alpha", 1e-6), ("shell_extent", 1e-6)],
    ] {
        let mut params = ParamSet::new();
        for (name, value) in pairs {
            params.set_float(name, value);
        }
        let m = medium_from_params(&params).unwrap();
        assert!(m.height.top().is_finite(), "{pairs:?}");
        let d = DVec3::new(0.6, 0.0, -0.8);
        for f in [-1e300, -1.0, 0.0, 1e-300, 1.0] {
            let (s, tau) = (m.sigma_t(f * m.height.sigma, d), m.optical_depth(f * m.height.sigma, d, 1.0));
            assert!(!s.is_nan() && !tau.is_nan() && s >= 0.0 && tau >= 0.0, "{pairs:?}, f {f}: sigma_t {s}, tau {tau}");
        }
    }
}

/// Item 12: a mean that answers NaN stops the march at once (it took 400 004 calls): at most 5
/// calls from the first NaN on.
#[test]
fn item12_nan_mean_stops_the_march_at_once() {
    let g = gpis("renewal_plus");
    let d = DVec3::new(0.3, 0.0, -0.9).normalize();
    let mut most_after_nan = 0;
    for nan_after in [0, 1, 2, 3, 5, 8, 20] {
        for start in [StartState::Uncorrelated, StartState::OnSurface { gradient: Some(DVec3::Z) }, StartState::OnSurface { gradient: None }] {
            let mean = CountingMean { plane: Plane { height: 0.0 }, calls: Cell::new(0), nan_after };
            let mut rng = Pcg32::new(1, 1);
            let origin = if start == StartState::Uncorrelated { DVec3::new(0.0, 0.0, 10.0) } else { DVec3::ZERO };
            let trace = g.trace(&mean, &Constant, origin, d, f64::INFINITY, &start, &mut || rng.next_f64()).unwrap();
            let calls = mean.calls.get();
            if calls > nan_after {
                assert!(matches!(trace, Trace::InvalidMean { .. }), "NaN from call {}: {trace:?}", nan_after + 1);
                most_after_nan = most_after_nan.max(calls - nan_after);
            } else {
                assert!(matches!(trace, Trace::Hit(_) | Trace::Miss), "{trace:?}");
            }
        }
    }
    // The NaN call itself, at most three gradient components of the memory, one more value.
    assert!(most_after_nan <= 5, "up to {most_after_nan} calls from the first NaN to the end of the march");
    // A Renewal+ start gradient no crossing can have is refused before the march.
    let plane = Plane { height: 0.0 };
    for bad in [DVec3::new(f64::MAX, 0.0, 1.0), DVec3::new(0.0, 0.0, 1e6), DVec3::new(0.0, -40.0, 1.0)] {
        let message = g.check_start_gradient(&plane, &Constant, DVec3::ZERO, bad).unwrap_err().message;
        assert!(message.contains("start.gradient"), "{bad}: {message}");
    }
    g.check_start_gradient(&plane, &Constant, DVec3::ZERO, DVec3::new(0.3, -0.2, 1.1)).unwrap();
}

/// Item 13: a gpis medium with α = 1e5 took over 20 s at 16² pixels: a march across the band
/// that needs more than 1e4 samples is refused, naming the parameters to change.
#[test]
fn item13_gpis_marches_are_bounded() {
    let message = medium_gpis_error(&[("sigma", 1.0), ("alpha", 1e5)]);
    assert!(message.contains("samples") && message.contains("shell_extent") && message.contains("step_correlation"), "{message}");
    assert!(medium_gpis_error(&[("sigma", 1.0), ("alpha", 10.0), ("step_correlation", 0.99999)]).contains("samples"));
    // The largest roughness that passes at the defaults (k = 6, rho = 0.95) is about 377.
    let mut params = ParamSet::new();
    params.set_float("sigma", 1.0).set_float("alpha", 370.0);
    gpis_from_params(&params).unwrap();
}

fn medium_gpis_error(pairs: &[(&str, f64)]) -> String {
    let mut params = ParamSet::new();
    for (name, value) in pairs {
        params.set_float(name, *value);
    }
    gpis_from_params(&params).unwrap_err().message
}

/// Found by fuzzing (`fuzz/`, target `params` and `phase`): samples from the very end of the
/// visible-normal distribution (`u[0] → 0`: `wi·m → 0`) had `pdf` formed through `wi·m D(m)`,
/// which underflows, so `weight ≠ eval/pdf` by up to 1e-3 — and a subnormal `pdf` made it noise.
/// gpss α = 0.0369 with copper flakes, seen from the normal and from 83.5°.
#[test]
fn fuzz_grazing_visible_normals_keep_weight_equal_to_eval_over_pdf() {
    let mut params = ParamSet::new();
    params.set_float("sigma", 1e50).set_float("alpha", 3.688588901449696e-2).set_string("material", "Cu");
    let phase = medium_from_params(&params).unwrap().phase;
    let tiny = [0.0, 5e-324, 1e-300, 1e-200, 1e-100, 1e-50, 1e-20, 1e-10];
    let mut valid = 0;
    for wi in [DVec3::Z, DVec3::new(-0.9307737412304455, 0.3474575593011919, 0.11372549019607847).normalize()] {
        for u0 in tiny {
            for u1 in [0.0, 0.25, 0.5, 0.9] {
                for u2 in [0.0, 0.3, 0.7] {
                    let Some(s) = phase.sample(wi, [u0, u1, u2, 0.0, 0.0]) else { continue };
                    valid += 1;
                    assert!(s.pdf >= f64::MIN_POSITIVE && s.pdf.to_bits() == phase.pdf(wi, s.wo).to_bits(), "wi {wi}, u0 {u0}: {s:?}");
                    let eval = phase.eval(wi, s.wo);
                    for (w, e) in s.weight.iter().zip(eval) {
                        assert!(relative(*w, e / s.pdf) < 1e-12, "wi {wi}, u {u0} {u1} {u2}: weight {:?}, eval/pdf {}", s.weight, e / s.pdf);
                    }
                }
            }
        }
    }
    assert!(valid > 50, "{valid} valid samples");
}

/// Found by fuzzing (target `params`): a conductor of index `eta = 1, k = 0` (no interface) had a
/// reflectance of −4.6e-17 from the cancelling difference form, and with it a negative weight.
#[test]
fn fuzz_fresnel_reflectance_stays_in_the_unit_interval() {
    use macrofacet::fresnel::fresnel_conductor;
    for (eta, k) in [(1.0, 0.0), (1.0, 1e-3), (1.0000000002018387, 0.0), (1e-6, 0.0), (1e6, 1e6), (0.5, 0.0), (2.0, 0.0)] {
        for i in 0..=1000 {
            let cos = i as f64 / 1000.0;
            let f = fresnel_conductor(cos, eta, k);
            assert!((0.0..=1.0).contains(&f), "F({cos}, {eta}, {k}) = {f}");
        }
    }
    assert!(fresnel_conductor(0.3, 1.0, 0.0) < 1e-30, "eta = 1: no interface");
    // The fuzz case: gpss height field with seeds/000 Eq. 40 sampling, eta = (1, 1, 0.01), k = (0, 10.2, 1e-3).
    let mut params = ParamSet::new();
    params.set_float("variance", 3.874675120456049e10).set_float("shell_extent", 0.3495).set_float("alpha_u", 4.318).set_float("alpha_v", 4.318);
    params.set_float("alpha_z", 0.0).set_rgb("eta", [1.0, 1.0, 0.01]).set_rgb("k", [0.0, 10.2, 1.0256e-3]);
    params.set_string("vndf_sampling", "mixture").set_float("mixture_ratio", 3.6517412725447255e-6);
    let phase = medium_from_params(&params).unwrap().phase;
    let mut rng = Pcg32::new(4, 6);
    for _ in 0..20_000 {
        let wi = direction(&mut rng, false);
        if let Some(s) = phase.sample(wi, u5(&mut rng)) {
            assert!(s.weight.iter().all(|w| *w >= 0.0 && w.is_finite()), "wi {wi}: {s:?}");
        }
    }
}

/// A mean that is no signed distance: a constant far inside.
struct ConstantMean(f64);

impl MeanSdf for ConstantMean {
    fn value(&self, _p: DVec3) -> f64 {
        self.0
    }
    fn gradient(&self, _p: DVec3) -> DVec3 {
        DVec3::new(0.0, 0.0, 1e-16)
    }
}

/// Found by fuzzing (target `gpis`): a free start where the mean is 5e8 σ inside drew its
/// conditioned value `f(o) > 0` as `m + σ z`, which rounds to ≤ 0, and reported a hit at t = 0.
#[test]
fn fuzz_free_start_deep_inside_hits_at_positive_t() {
    let mut params = ParamSet::new();
    params.set_float("sigma", 1.936285764540805e-8).set_float("alpha", 10.0).set_string("memory", "renewal").set_float("step_correlation", 0.999);
    let g = gpis_from_params(&params).unwrap();
    let mean = ConstantMean(-9.9794145972893);
    let origin = DVec3::new(-4.857496975429136e-8, -7.846958366760742e-9, -2.5117410024212405e-9);
    let d = DVec3::new(-0.1494087068867229, 0.9758640322680162, -0.15926841755993526).normalize();
    for seed in 0..200u64 {
        let mut rng = Pcg32::new(seed, 0x6d66_6770_6973);
        match g.trace(&mean, &Constant, origin, d, f64::INFINITY, &StartState::Uncorrelated, &mut || rng.next_f64()).unwrap() {
            Trace::Hit(c) => assert!(c.t > 0.0 && c.t.is_finite(), "seed {seed}: t = {}", c.t),
            other => panic!("seed {seed}: {other:?}"),
        }
    }
}

