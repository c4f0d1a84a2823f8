//! Issue 9 item 2: a segment parallel to the shell, above its top, with `t_max = +inf`
//! (σ = 1, α = 0.3, n = +z, d = (1, 0, 0), f = 3.5, where σ_t = 0): `optical_depth` was inf,
//! `transmittance` 0 and `sample_free_flight` scattered at `t = −inf`; with `t_max = 1e10` all
//! three were right. Also what `fuzz/` found in the planar closed forms since.

use glam::DVec3;
use macrofacet_ffi::*;
use macrofacet::{medium_from_params, FreeFlight, MacrofacetMedium, ParamSet};
use std::ffi::CString;
use std::ptr;

/// A medium from float parameters and, optionally, a `distribution`.
fn medium(floats: &[(&str, f64)], distribution: &str) -> MacrofacetMedium {
    let mut params = ParamSet::new();
    for (name, value) in floats {
        params.set_float(name, *value);
    }
    params.set_string("distribution", distribution);
    medium_from_params(&params).unwrap()
}

#[test]
fn item2_segment_above_the_shell_parallel_to_it_passes() {
    let medium = medium(&[("sigma", 1.0), ("alpha", 0.3)], "gpss");
    let d = DVec3::X;
    for t_max in [1e10, f64::INFINITY] {
        assert_eq!(medium.sigma_t(3.5, d), 0.0);
        assert_eq!(medium.optical_depth(3.5, d, t_max), 0.0, "t_max {t_max}");
        assert_eq!(medium.transmittance(3.5, d, t_max), 1.0, "t_max {t_max}");
        for u in [0.0, 0.3, 0.999] {
            assert_eq!(medium.sample_free_flight(3.5, d, t_max, u), FreeFlight::Pass, "t_max {t_max}, u {u}");
        }
    }

    // The same through the C ABI.
    let mut handle: *mut mf_params = ptr::null_mut();
    let mut m: *mut mf_medium = ptr::null_mut();
    unsafe {
        assert_eq!(mf_params_new(&mut handle), mf_status::MF_OK);
        for (name, value) in [("sigma", 1.0), ("alpha", 0.3)] {
            assert_eq!(mf_params_set_float(handle, CString::new(name).unwrap().as_ptr(), value), mf_status::MF_OK);
        }
        assert_eq!(mf_medium_new(handle, &mut m), mf_status::MF_OK);
        mf_params_free(handle);
        let frame = mf_frame { normal: mf_vec3 { x: 0.0, y: 0.0, z: 1.0 }, tangent: mf_vec3 { x: 1.0, y: 0.0, z: 0.0 } };
        let d = mf_vec3 { x: 1.0, y: 0.0, z: 0.0 };
        let (mut tau, mut transmittance) = (f64::NAN, f64::NAN);
        let mut flight = mf_free_flight { scattered: true, t: f64::NAN };
        assert_eq!(mf_medium_optical_depth(m, &frame, 3.5, d, f64::INFINITY, &mut tau), mf_status::MF_OK);
        assert_eq!(mf_medium_transmittance(m, &frame, 3.5, d, f64::INFINITY, &mut transmittance), mf_status::MF_OK);
        assert_eq!(mf_medium_sample_free_flight(m, &frame, 3.5, d, f64::INFINITY, 0.5, &mut flight), mf_status::MF_OK);
        assert_eq!((tau, transmittance), (0.0, 1.0));
        assert!(!flight.scattered && flight.t == f64::INFINITY, "{flight:?}");
        mf_medium_free(m);
    }
}

/// Found by fuzzing (`fuzz/`, target `medium_queries`): a segment from the top face (f = kσ)
/// rising at `d_z = 1e-16` lies above the shell for every `s > 0` (τ = 0), but where
/// `f0 + t d_z` rounds back to `f0` it was counted inside for its whole length: T(1) = 0.99962
/// while T(1e10) = 1 (and at σ = 1e50: T = 3e-52 for a shorter segment, 1 for a longer one).
#[test]
fn fuzz_segment_rising_from_the_top_face_is_above_the_shell() {
    let medium = medium(&[("sigma", 1.0), ("alpha", 0.3)], "gpss");
    let d = DVec3::new(0.0, 1.0, 1e-16);
    for t in [1.0, 1e3, 1e10, f64::INFINITY] {
        assert_eq!(medium.transmittance(3.0, d, t), 1.0, "t = {t}");
    }
}


/// Found by fuzzing (`fuzz/`, target `medium_queries`): above the shell, descending so slowly
/// (`d_z = -1e-320`) that the shell is reached only beyond `f64::MAX`, with `t_max = +inf`: the
/// flight "scattered" at `t = +inf`. No collision lies within the range of `f64`: a pass.
#[test]
fn fuzz_shell_reached_beyond_f64_max_is_a_pass() {
    let medium = medium(&[("sigma", 1.0), ("alpha", 0.3)], "gpss");
    let d = DVec3::new(1.0, 0.0, -1e-320);
    for u in [0.0, 0.5, 0.999] {
        match medium.sample_free_flight(3.5, d, f64::INFINITY, u) {
            FreeFlight::Pass => {}
            FreeFlight::Scatter { t } => assert!(t.is_finite(), "u {u}: scattered at t = {t}"),
        }
    }
}

/// Found by fuzzing (`fuzz/`, target `medium_queries`): deep inside, where the flake density
/// overflows (`f = -1e308`, σ = 0.5), a segment of length 5e-324 has τ ≈ t ρ(f) ≈ 1e-15, but the
/// nearly horizontal branch formed `s · t · inf` with `s · t = 0`: τ = NaN, T = NaN.
#[test]
fn fuzz_short_segment_where_the_density_overflows_is_not_nan() {
    let medium = medium(&[("sigma", 0.5), ("lengthscale", 1e4)], "beckmann");
    let d = DVec3::new(0.0, 1.0, 1e-16);
    for (f, t) in [(-f64::MAX, 5e-324), (-1e308, 5e-324), (-1e308, 1e-300)] {
        let tau = medium.optical_depth(f, d, t);
        assert!(tau >= 0.0, "f {f:e}, t {t:e}: tau {tau}");
        assert!((0.0..=1.0).contains(&medium.transmittance(f, d, t)), "f {f:e}, t {t:e}");
    }
}

/// Found by fuzzing (`fuzz/`, target `medium_queries`): beyond `|f| = 1.34e154 σ`,
/// `ln Φ(f/σ) = −f²/2σ²` overflows to `−inf` and the optical depth of a long segment deep inside
/// came out `(−inf) − (−inf)` → 0 (T = 1 where the segment is opaque; a shorter one gave T = 0).
#[test]
fn fuzz_long_segment_far_inside_is_opaque() {
    let medium = medium(&[("variance", 1.0), ("lengthscale", 1.3335235968114107e-4)], "beckmann");
    let d = DVec3::new(0.0, 1.0, 1e-16);
    for t in [3.8e243, 9.303092537463567e243] {
        assert_eq!(medium.transmittance(-9.303093617969135e243, d, t), 0.0, "t = {t:e}");
    }
}

/// Found by fuzzing (`fuzz/`, target `medium_queries`): the majorant over `[f_a, f_b]` is
/// `σ_t(min(f_a, f_b))`, but `ρ(f)` is not monotone at the scale of one ulp (its `erfcx` rounds):
/// one ulp above the lower end σ_t was larger by one ulp (1926037.444227884 vs ...838). A delta
/// tracker then accepts with probability `1 + 1e-16`.
#[test]
fn fuzz_majorant_bounds_sigma_t_at_both_ends() {
    let medium = medium(&[("variance", 1.0), ("alpha", 1e6)], "beckmann");
    let d = DVec3::new(0.468686519772254, 0.2369922326750911, 0.8509803921568628).normalize();
    let (f_a, f_b) = (-20.423529411764704, -20.423529411764708);
    let majorant = medium.majorant(f_a, f_b, d);
    assert!(majorant >= medium.sigma_t(f_a, d) && majorant >= medium.sigma_t(f_b, d), "{majorant}");
}

/// Found by fuzzing (`fuzz/`, target `medium_queries`): one ulp below a top face at 39.8σ
/// (σ = 1e50), rising at `d_z = 1e-300` to `t = +inf`, the nearly parallel rule formed
/// `∞ · 0` (the density underflows there): τ = NaN.
#[test]
fn fuzz_infinite_segment_where_the_density_underflows_is_not_nan() {
    let medium = medium(&[("sigma", 1e50), ("shell_extent", 3.9810717055349734e1), ("alpha", 1e6)], "ggx");
    let d = DVec3::new(0.0, 1.0, 1e-300);
    let f = 3.981071705534973e51;
    assert_eq!(medium.optical_depth(f, d, f64::INFINITY), 0.0);
    assert_eq!(medium.transmittance(f, d, f64::INFINITY), 1.0);
    assert_eq!(medium.sample_free_flight(f, d, f64::INFINITY, 0.999), FreeFlight::Pass);
}

/// Found by fuzzing (`fuzz/`, target `medium_queries`): one ulp below the top face, rising so
/// little that `f0 + t d_z` rounds onto the face, a segment of 2.8e-66 counted its whole length
/// inside while it leaves the shell after 2.7e-66, so it transmitted less than a segment 55×
/// longer.
#[test]
fn fuzz_longer_segment_from_below_the_top_face_transmits_no_more() {
    let mut params = ParamSet::new();
    params.set_float("sigma", 1e-50);
    params.set_float("shell_extent", 9.22239057924383e-1);
    params.set_float("lengthscale_x", 1.4142135623730952e-44);
    params.set_float("lengthscale_y", 1.4142135623730953e-56);
    params.set_string("distribution", "ggx");
    let medium = medium_from_params(&params).unwrap();
    let (f, d) = (9.222390579243828e-51, DVec3::new(0.3, 0.8, 0.487).normalize());
    let (short, long) = (2.7855618193418084e-66, 1.535836554474395e-64);
    assert!(medium.transmittance(f, d, short) >= medium.transmittance(f, d, long));
}

/// Found by fuzzing (`fuzz/`, target `medium_queries`): above the shell, descending at
/// `d_z = −2.8e-309` (a frame normal of length 1.8e308), the shell is entered at t = 1.7e308 and
/// the polishing bracket overflowed: the flight "scattered" at `t = +inf`.
#[test]
fn fuzz_shell_entered_near_f64_max_never_scatters_at_infinity() {
    let medium = medium(&[("variance", 4.855953393399506e-5), ("alpha", 0.5)], "gpss");
    let d = DVec3::new(-0.7071067811865475, 0.7071067811865475, -2.781342323134e-309);
    for u in [2.2250738585072014e-308, 0.5] {
        match medium.sample_free_flight(0.5, d, f64::INFINITY, u) {
            FreeFlight::Pass => {}
            FreeFlight::Scatter { t } => assert!(t.is_finite(), "u {u}: scattered at t = {t}"),
        }
    }
}

/// Found by fuzzing (`fuzz/`, target `medium_queries`): σ = 1e-50 and f = −5.4e258, where
/// f/σ itself overflows: the ln Φ difference was NaN (τ = 0, T = 1 deep inside, while a shorter
/// segment had T = 0).
#[test]
fn fuzz_segment_where_f_over_sigma_overflows_is_opaque() {
    let medium = medium(&[("sigma", 1e-50), ("lengthscale", 1.4142135623730952e-44)], "ggx");
    let d = DVec3::new(-0.8415352692495371, 0.532623858241003, -0.434).normalize();
    let f = -5.393079404586947e258;
    for t in [6.4e241, 5.4852485385018114e247] {
        assert_eq!(medium.transmittance(f, d, t), 0.0, "t = {t:e}");
    }
}
