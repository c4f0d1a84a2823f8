//! The distribution handle: `mf_ndf_new` (Beckmann, GGX, GTR with either Λ, anisotropic,
//! stretched, transformed, or any names and values), `mf_ndf_eval`, `mf_ndf_lambda`,
//! `mf_ndf_pdf_visible`, `mf_ndf_sample_visible`, `mf_ndf_free`. Properties: `D >= 0` and finite,
//! 0 below the horizon; Λ not NaN, finite off the horizon, `>= 0` above it and `<= -1` below,
//! `Λ(w) + Λ(-w) = -1`; `pdf_visible >= 0`; a valid sample has a unit `m` and the pdf of
//! `mf_ndf_pdf_visible` at it.
#![no_main]

use glam::DVec3;
use libfuzzer_sys::fuzz_target;
use macrofacet_ffi::*;
use macrofacet_fuzz::build;
use macrofacet_fuzz::check;
use macrofacet_fuzz::input::{dvec3, vec3, Bytes};
use std::ptr;

/// Within this |cos θ| of the horizon (as computed here, in world space: the library's local
/// cosine rounds differently by ~1e-16) Λ may be the horizon's ±inf. Beyond it Λ ~ α tan θ is
/// far below overflow.
const GRAZING: f64 = 1e-12;

fuzz_target!(|data: &[u8]| {
    let mut b = Bytes::new(data);
    let Some(ndf) = build::ndf(&build::ndf_params(&mut b)) else { return };
    for _ in 0..1 + b.below(2) {
        let frame = b.frame();
        let n = dvec3(frame.normal);
        let (wi, m) = (b.direction(n), b.direction(n));
        let u: [f64; MF_NDF_SAMPLE_DIMENSIONS] = b.uniforms();
        if std::env::var_os("MF_FUZZ_DEBUG").is_some() {
            eprintln!("query: frame {frame:?} wi {wi:?} m {m:?} u {u:?}");
        }
        // The cosine with the (normalised) frame normal, where the frame is valid.
        // (Scaled first: a normal of length 1e155 overflows a plain length.)
        let n = (n / n.abs().max_element()).try_normalize();
        let cos = |v: DVec3| n.map(|n| n.dot(v.normalize()));
        if let Ok(d) = check::call(|o| unsafe { mf_ndf_eval(ndf.0, &frame, vec3(m), o) }) {
            check::finite_nonnegative("D", d);
            if let Some(c) = cos(m) {
                assert!(c > -1e-9 || d == 0.0, "D = {d} below the horizon (cos {c})");
            }
        }
        for w in [wi, m] {
            let Ok(lambda) = check::call(|o| unsafe { mf_ndf_lambda(ndf.0, &frame, vec3(w), o) }) else { continue };
            let lambda_back = check::call(|o| unsafe { mf_ndf_lambda(ndf.0, &frame, vec3(-w), o) }).expect("Λ(-w) where Λ(w) was fine");
            assert!(!lambda.is_nan() && !lambda_back.is_nan(), "Λ({w}) = {lambda}, Λ(-w) = {lambda_back}");
            let Some(c) = cos(w) else { continue };
            if c.abs() >= GRAZING {
                assert!(lambda.is_finite(), "Λ({w}) = {lambda} off the horizon (cos {c})");
            }
            // (The cosine in world space rounds differently from the library's local one.)
            if c > 1e-12 {
                assert!(lambda >= -1e-12, "Λ = {lambda} above the horizon (cos {c})");
            } else if c < -1e-12 {
                assert!(lambda <= -1.0 + 1e-12, "Λ = {lambda} below the horizon (cos {c})");
            }
            if lambda.is_finite() && lambda_back.is_finite() {
                assert!((lambda + lambda_back + 1.0).abs() <= 1e-9 * lambda.abs().max(1.0), "Λ(w) + Λ(-w) = {lambda} + {lambda_back} != -1");
            }
        }
        if let Ok(pdf) = check::call(|o| unsafe { mf_ndf_pdf_visible(ndf.0, &frame, vec3(wi), vec3(m), o) }) {
            check::finite_nonnegative("pdf_visible", pdf);
        }
        if let Ok(s) = check::call(|o| unsafe { mf_ndf_sample_visible(ndf.0, &frame, vec3(wi), u.as_ptr(), o) }) {
            let pdf = if s.valid { check::call(|o| unsafe { mf_ndf_pdf_visible(ndf.0, &frame, vec3(wi), s.m, o) }).expect("pdf of a sampled normal") } else { 0.0 };
            // The sample's pdf is that of the returned m: equal to mf_ndf_pdf_visible bit for bit.
            check::ndf_sample(&s, pdf, 0.0);
            if s.valid {
                let d = check::call(|o| unsafe { mf_ndf_eval(ndf.0, &frame, s.m, o) }).expect("D of a sampled normal");
                assert!(d > 0.0, "a sampled normal with D = {d}");
            }
        }
        if b.u8() % 16 == 0 {
            check::null_out(|o| unsafe { mf_ndf_eval(ndf.0, &frame, vec3(m), o) });
            check::null_out(|o| unsafe { mf_ndf_lambda(ndf.0, &frame, vec3(wi), o) });
            check::null_out(|o| unsafe { mf_ndf_pdf_visible(ndf.0, &frame, vec3(wi), vec3(m), o) });
            check::null_out(|o| unsafe { mf_ndf_sample_visible(ndf.0, &frame, vec3(wi), u.as_ptr(), o) });
            assert!(check::call(|o| unsafe { mf_ndf_sample_visible(ndf.0, &frame, vec3(wi), ptr::null(), o) }).is_err());
            assert!(check::call(|o| unsafe { mf_ndf_eval(ptr::null(), &frame, vec3(m), o) }).is_err());
            assert!(check::call(|o| unsafe { mf_ndf_lambda(ndf.0, ptr::null(), vec3(wi), o) }).is_err());
            let handle = build::params_handle(&[]);
            check::null_out(|o| unsafe { mf_ndf_new(handle.0, o) });
            assert!(check::call(|o| unsafe { mf_ndf_new(ptr::null(), o) }).is_err());
            unsafe { mf_ndf_free(ptr::null_mut()) };
        }
    }
});
