//! Regression tests for what the `ndf` fuzz target found (issue 9, `fuzz/fuzz_targets/ndf.rs`).

use macrofacet_ffi::*;
use std::ffi::CString;
use std::ptr;

fn ndf(floats: &[(&str, f64)], strings: &[(&str, &str)]) -> *mut mf_ndf {
    let (mut params, mut ndf) = (ptr::null_mut(), ptr::null_mut());
    unsafe {
        assert_eq!(mf_params_new(&mut params), mf_status::MF_OK);
        for (name, x) in floats {
            let name = CString::new(*name).unwrap();
            assert_eq!(mf_params_set_float(params, name.as_ptr(), *x), mf_status::MF_OK);
        }
        for (name, s) in strings {
            let (name, s) = (CString::new(*name).unwrap(), CString::new(*s).unwrap());
            assert_eq!(mf_params_set_string(params, name.as_ptr(), s.as_ptr()), mf_status::MF_OK);
        }
        assert_eq!(mf_ndf_new(params, &mut ndf), mf_status::MF_OK);
        mf_params_free(params);
    }
    ndf
}

/// `fuzz/artifacts/ndf/crash-2dbf9a1d9b1d55c4d063bd891c4a99c38c782deb`: Beckmann α = 1e-4,
/// `wi` 0.0029 rad off the normal, `u = (0, 0, 0)` (inside [0, 1)): `mf_ndf_sample_visible`
/// returns `valid = 1` with `pdf = 0` (the sampled normal sits where `D` underflows), which a
/// host divides by. A valid sample must have `pdf > 0` equal to `mf_ndf_pdf_visible` at it (or
/// the sample be invalid), as issue 9 asks of every sampler (its item 4 for the phase function).
#[test]
fn visible_normal_sample_at_u_zero_has_positive_pdf() {
    let n = ndf(&[("alpha", 1e-4)], &[]);
    let frame = mf_frame { normal: mf_vec3 { x: 0.0, y: 0.0, z: 1.0 }, tangent: mf_vec3 { x: 0.0, y: 0.0, z: 1.0 } };
    let wi = mf_vec3 { x: 0.00293383020488917, y: 0.0, z: 0.9999956963109036 };
    let u = [0.0; MF_NDF_SAMPLE_DIMENSIONS];
    let mut s = mf_ndf_sample { m: mf_vec3 { x: 0.0, y: 0.0, z: 0.0 }, pdf: -1.0, valid: false };
    assert_eq!(unsafe { mf_ndf_sample_visible(n, &frame, wi, u.as_ptr(), &mut s) }, mf_status::MF_OK);
    if s.valid {
        let mut pdf = -1.0;
        assert_eq!(unsafe { mf_ndf_pdf_visible(n, &frame, wi, s.m, &mut pdf) }, mf_status::MF_OK);
        assert!(s.pdf > 0.0 && pdf > 0.0, "{s:?}, mf_ndf_pdf_visible {pdf}");
    }
    unsafe { mf_ndf_free(n) };
}

/// `fuzz/artifacts/ndf/crash-b2fd1f03ea7fb844ce6f5671275aacf330593548`: Beckmann α = 1e-4,
/// frame normal (0.4985, 0.3718, 0.7831), `wi` at cos θ ≈ 3e-6 from the horizon, `u = (0, 0, 0)`:
/// the sample's pdf 0.6086727596360527 but `mf_ndf_pdf_visible` at its `m` 0.608604570685825,
/// 1.1e-4 apart (the world-space round trip of `m` accounts for ~1e-10 here). Both must agree
/// to rounding (bit for bit, as `mf_phase_sample` promises, if the pdf is computed from the
/// returned `m`).
#[test]
fn visible_normal_sample_pdf_matches_pdf_visible_at_u_zero() {
    let n = ndf(&[("alpha", 1e-4)], &[]);
    let normal = mf_vec3 { x: 0.4985407418895696, y: 0.37175481201086974, z: 0.7831063072297149 };
    let frame = mf_frame { normal, tangent: normal };
    let wi = mf_vec3 { x: -0.10393935018902305, y: 0.9224938899805881, z: -0.37175480417980666 };
    let u = [0.0; MF_NDF_SAMPLE_DIMENSIONS];
    let mut s = mf_ndf_sample { m: mf_vec3 { x: 0.0, y: 0.0, z: 0.0 }, pdf: -1.0, valid: false };
    assert_eq!(unsafe { mf_ndf_sample_visible(n, &frame, wi, u.as_ptr(), &mut s) }, mf_status::MF_OK);
    if s.valid {
        let mut pdf = -1.0;
        assert_eq!(unsafe { mf_ndf_pdf_visible(n, &frame, wi, s.m, &mut pdf) }, mf_status::MF_OK);
        assert!((s.pdf - pdf).abs() <= 1e-9 * pdf, "{s:?}, mf_ndf_pdf_visible {pdf}");
    }
    unsafe { mf_ndf_free(n) };
}

/// `fuzz/artifacts/ndf/crash-67a47dfe32a5e4bbaf547bc19dc06ccfb4425978`: GTR γ = 4,
/// α = 1000.0000000010001, frame normal (-3, 8.8e-153, 3.4e125) (so `w = +z` lies 8.9e-126 rad
/// off it): `mf_ndf_lambda` answers NaN with MF_OK, for `w` and `-w`. NaN is never a valid MF_OK
/// output; near the normal Λ = 0 (and Λ(-w) = -1). Exactly along the normal (frame +z) it is
/// right: the NaN comes from a tan θ of ~1e-125 (an overflow of 1/tan² or similar in GTR's Λ).
#[test]
fn gtr_lambda_near_the_normal_is_not_nan() {
    let n = ndf(&[("gamma", 4.0), ("alpha", 1.0000000000010001e3)], &[("distribution", "gtr")]);
    let normal = mf_vec3 { x: -3.0, y: 8.765161841414401e-153, z: 3.38462269926781e125 };
    let up = mf_vec3 { x: 0.0, y: 0.0, z: 1.0 };
    for (frame, name) in [(mf_frame { normal: up, tangent: up }, "frame +z"), (mf_frame { normal, tangent: normal }, "artifact frame")] {
        for w in [up, mf_vec3 { x: 0.0, y: 0.0, z: -1.0 }] {
            let mut lambda = -7.0;
            assert_eq!(unsafe { mf_ndf_lambda(n, &frame, w, &mut lambda) }, mf_status::MF_OK);
            assert!(!lambda.is_nan(), "{name}, w = {w:?}: Λ = {lambda}");
        }
    }
    unsafe { mf_ndf_free(n) };
}

/// `fuzz/artifacts/ndf/crash-bd026eae994a6584250bd97cbb4461017675fd83` (found once the fuzz
/// target stopped skipping the case above): GTR γ = 3, α = 1000.0000000010001, frame normal
/// (-3.1e-97, -5.2e-99, 6.55), so `w = +z` lies 4.8e-98 rad off it (μ = cot θ = 2.1e97, below the
/// 1e100 where the excess is skipped): `mf_ndf_lambda` answered −∞ with MF_OK, from `μ³ a2²`
/// overflowing inside GTR_4's excess. Near the normal Λ(w) = 0 and Λ(−w) = −1.
#[test]
fn gtr_lambda_near_the_normal_is_finite() {
    let n = ndf(&[("gamma", 3.0), ("alpha", 1.0000000000010001e3)], &[("distribution", "gtr")]);
    let frame = mf_frame { normal: mf_vec3 { x: -3.1367874596608137e-97, y: -5.1777413071657925e-99, z: 6.54887483179553 }, tangent: mf_vec3 { x: 1.0, y: 0.0, z: 0.0 } };
    for (w, expected) in [(1.0, 0.0), (-1.0, -1.0)] {
        let mut lambda = -7.0;
        assert_eq!(unsafe { mf_ndf_lambda(n, &frame, mf_vec3 { x: 0.0, y: 0.0, z: w }, &mut lambda) }, mf_status::MF_OK);
        assert!((lambda - expected).abs() <= 1e-12, "w = {w}: Λ = {lambda}, expected {expected}");
    }
    unsafe { mf_ndf_free(n) };
}

/// `fuzz/artifacts/ndf/crash-45e43ad95b1c47e52c48f8e688b6b46fd9b19cb5`: GTR γ = 2.2902,
/// α = 1.0003e-4, stretch 0.9843, frame normal (-3, 4.17e62, 1e6) (≈ +y), `wi = -y` (below the
/// surface), u = (0.99216, 0.10436, 0.57256): `mf_ndf_sample_visible` returns a valid sample with
/// pdf 5.97e18 where `mf_ndf_pdf_visible` says 0. A sample and the density of the same call must
/// agree (or the sample be invalid when no facet is visible from `wi`).
#[test]
fn visible_normal_sample_from_below_agrees_with_pdf_visible() {
    let n = ndf(&[("gamma", 2.290196078431898), ("alpha", 1.0003316255674524e-4), ("stretch", 9.84271522612481e-1)], &[("distribution", "gtr")]);
    let normal = mf_vec3 { x: -3.0, y: 4.1720279211547985e62, z: 1000000.0 };
    let frame = mf_frame { normal, tangent: normal };
    let wi = mf_vec3 { x: -0.0, y: -1.0, z: -0.0 };
    let u = [0.9921568626095811, 0.10436356675433756, 0.5725554223154105];
    let mut s = mf_ndf_sample { m: mf_vec3 { x: 0.0, y: 0.0, z: 0.0 }, pdf: -1.0, valid: false };
    assert_eq!(unsafe { mf_ndf_sample_visible(n, &frame, wi, u.as_ptr(), &mut s) }, mf_status::MF_OK);
    if s.valid {
        let mut pdf = -1.0;
        assert_eq!(unsafe { mf_ndf_pdf_visible(n, &frame, wi, s.m, &mut pdf) }, mf_status::MF_OK);
        assert!((s.pdf - pdf).abs() <= 1e-9 * pdf, "{s:?}, mf_ndf_pdf_visible {pdf}");
    }
    unsafe { mf_ndf_free(n) };
}

/// `fuzz/artifacts/ndf/crash-f54e813106abbca2dd61918a3604d1b587b18e1c`: Beckmann
/// α = 1.2953245738982308e-4, frame normal (2, 2.761434871387058e154, 7.155e-307) (≈ +y, of
/// length 2.8e154), `wi = (0, 1, 1e-300)` (along the normal), u = (0.97647053, 0.97647059,
/// 0.97647059) — not at an edge: `mf_ndf_sample_visible` returns a valid sample with pdf 0, its
/// `m` = (1, 8e-137, -2e-140), on the horizon. The frame itself is right (`Frame` rescales the
/// normal); suspected: `wi` lies ~1e-154 rad off the normal, so its local tangential components
/// are ~1e-154 and their squares underflow in the sampler's azimuth (sin θ = 0 with x, y ≠ 0).
#[test]
fn visible_normal_sample_with_a_long_frame_normal_has_positive_pdf() {
    let n = ndf(&[("alpha", 1.2953245738982308e-4)], &[("distribution", "beckmann")]);
    let normal = mf_vec3 { x: 2.0, y: 2.761434871387058e154, z: 7.155003126312e-307 };
    let frame = mf_frame { normal, tangent: normal };
    let wi = mf_vec3 { x: 0.0, y: 1.0, z: 1e-300 };
    let u = [0.9764705300331132, 0.9764705882352941, 0.9764705882352941];
    let mut s = mf_ndf_sample { m: mf_vec3 { x: 0.0, y: 0.0, z: 0.0 }, pdf: -1.0, valid: false };
    assert_eq!(unsafe { mf_ndf_sample_visible(n, &frame, wi, u.as_ptr(), &mut s) }, mf_status::MF_OK);
    assert!(!s.valid || s.pdf > 0.0, "{s:?}");
    unsafe { mf_ndf_free(n) };
}

/// `fuzz/artifacts/ndf/crash-4d1d8869fd79689bd673c53a972149b6f06ebf78`: GTR (γ = 0.235, Dimov's
/// Λ) with α_u = 0.131, α_v = 1.1e-4, `w` along the tangent plane with `w_z = −1e-320`
/// (subnormal): `Λ(w) + Λ(−w)` was −1.0074, not −1 (seeds/000 Eq. 39), because both were
/// quotients of areas that had lost their digits. Below the horizon Λ now comes from the
/// identity, for every distribution and every `w_z`.
#[test]
fn lambda_identity_holds_at_subnormal_cosines() {
    let gtr = ndf(&[("gamma", 2.3529411781422027e-1), ("alpha_u", 1.3105453383053872e-1), ("alpha_v", 1.1347556922028417e-4)], &[("distribution", "gtr"), ("lambda", "dimov")]);
    let beckmann = ndf(&[("alpha", 0.3)], &[]);
    let frame = mf_frame { normal: mf_vec3 { x: 0.0, y: 0.0, z: 1.0 }, tangent: mf_vec3 { x: 0.0, y: 0.0, z: 1.0 } };
    for n in [gtr, beckmann] {
        for z in [-1e-320f64, -5e-324, -1e-310, -1e-300, -1e-100, -1e-16, -1e-8, -0.3] {
            let w = mf_vec3 { x: 0.0, y: (1.0 - z * z).sqrt(), z };
            let (mut below, mut above) = (f64::NAN, f64::NAN);
            assert_eq!(unsafe { mf_ndf_lambda(n, &frame, w, &mut below) }, mf_status::MF_OK);
            assert_eq!(unsafe { mf_ndf_lambda(n, &frame, mf_vec3 { x: -w.x, y: -w.y, z: -w.z }, &mut above) }, mf_status::MF_OK);
            if below.is_finite() && above.is_finite() {
                assert!((below + above + 1.0).abs() <= 1e-9 * below.abs().max(1.0), "w_z {z:e}: Λ(w) + Λ(−w) = {below} + {above}");
            }
        }
        unsafe { mf_ndf_free(n) };
    }
}

/// `fuzz/artifacts/ndf/crash-e1b26edcdf7524a61889997136180c2e1ea9354b`: GTR (γ = 3) with the
/// transform `[[5e5, 2e155], [2e155, 5e5]]`: its determinant overflowed to −∞, which passed the
/// invertibility check (`|det| > 1e-12 × scale²` with the product evaluated left to right), and
/// `mf_ndf_eval` answered D = NaN with MF_OK at `m = −y` (`|Mᵀm|²` overflowed). Entries beyond
/// ±1e12 are refused with the reason.
#[test]
fn overflowing_microsurface_transform_is_refused() {
    let floats = [("gamma", 3.0), ("alpha", 9.99999999999e-5), ("transform_xx", 5e5), ("transform_xy", 2.0408163340358347e155), ("transform_yx", 2.040816332656715e155), ("transform_yy", 5e5)];
    let (mut params, mut n) = (ptr::null_mut(), ptr::null_mut());
    unsafe {
        assert_eq!(mf_params_new(&mut params), mf_status::MF_OK);
        for (name, x) in floats {
            let name = CString::new(name).unwrap();
            assert_eq!(mf_params_set_float(params, name.as_ptr(), x), mf_status::MF_OK);
        }
        for (name, s) in [("distribution", "gtr"), ("lambda", "dimov")] {
            let (name, s) = (CString::new(name).unwrap(), CString::new(s).unwrap());
            assert_eq!(mf_params_set_string(params, name.as_ptr(), s.as_ptr()), mf_status::MF_OK);
        }
        assert_ne!(mf_ndf_new(params, &mut n), mf_status::MF_OK);
        assert!(n.is_null(), "nothing written on failure");
        mf_params_free(params);
    }
    // The largest accepted entries evaluate to finite numbers.
    let n = ndf(&[("gamma", 3.0), ("alpha", 1e-4), ("transform_xx", 5e5), ("transform_xy", 1e12), ("transform_yx", 1e12), ("transform_yy", 5e5)], &[("distribution", "gtr"), ("lambda", "dimov")]);
    let frame = mf_frame { normal: mf_vec3 { x: 3.0486221039776374e-302, y: -9.367720411159655e-301, z: 3.486097148820466e-301 }, tangent: mf_vec3 { x: 0.0, y: 0.0, z: 0.0 } };
    for m in [mf_vec3 { x: -0.0, y: -1.0, z: -0.0 }, mf_vec3 { x: 0.6, y: -0.8, z: 0.0 }] {
        let mut d = -1.0;
        assert_eq!(unsafe { mf_ndf_eval(n, &frame, m, &mut d) }, mf_status::MF_OK);
        assert!(d.is_finite() && d >= 0.0, "D = {d}");
    }
    unsafe { mf_ndf_free(n) };
}
