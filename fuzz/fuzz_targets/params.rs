//! Parameter parsing: `mf_params_*` with any names, types and values, then `mf_medium_new` and
//! `mf_gpis_new`. A refusal must leave the out-parameter untouched and say why; an accepted
//! parameter set must give a medium whose basic queries answer with finite numbers.
#![no_main]

use libfuzzer_sys::fuzz_target;
use macrofacet_ffi::*;
use macrofacet_fuzz::build::{self, Param};
use macrofacet_fuzz::check;
use macrofacet_fuzz::input::{vec3, Bytes};
use std::ptr;

fuzz_target!(|data: &[u8]| {
    let mut b = Bytes::new(data);
    let mut params: Vec<Param> = match b.u8() % 4 {
        0 => build::medium_params(&mut b),
        1 => build::gpis_params(&mut b),
        _ => build::arbitrary_params(&mut b),
    };
    if b.u8() % 4 == 0 {
        params.extend(build::arbitrary_params(&mut b));
    }
    if let Some(m) = build::medium(&params) {
        medium_answers(&m, &mut b);
    }
    if let Some(g) = build::gpis(&params) {
        let envelope = check::call(|o| unsafe { mf_gpis_envelope(g.0, ptr::null(), o) }).expect("mf_gpis_envelope");
        assert!(envelope > 0.0 && envelope.is_finite(), "envelope {envelope}");
    }
    // NULL arguments.
    let handle = build::params_handle(&params);
    check::null_out(|o| unsafe { mf_medium_new(handle.0, o) });
    check::null_out(|o| unsafe { mf_gpis_new(handle.0, o) });
    assert!(check::call(|o| unsafe { mf_medium_new(std::ptr::null(), o) }).is_err());
    assert!(check::call(|o| unsafe { mf_gpis_new(std::ptr::null(), o) }).is_err());
    let name = c"sigma";
    assert!(check::status(unsafe { mf_params_set_float(std::ptr::null_mut(), name.as_ptr(), 1.0) }).is_err());
    assert!(check::status(unsafe { mf_params_set_float(handle.0, std::ptr::null(), 1.0) }).is_err());
    assert!(check::status(unsafe { mf_params_set_rgb(handle.0, name.as_ptr(), std::ptr::null()) }).is_err());
    assert!(check::status(unsafe { mf_params_set_string(handle.0, name.as_ptr(), std::ptr::null()) }).is_err());
    check::null_out(|o: *mut *mut mf_params| unsafe { mf_params_new(o) });
});

/// An accepted medium answers its basic queries with finite numbers: the shell top, the
/// extinction and optical depth of a segment into the surface, and a phase sample at normal
/// incidence.
fn medium_answers(m: &build::Medium, b: &mut Bytes) {
    let top = check::call(|o| unsafe { mf_medium_shell_top(m.0, o) }).expect("mf_medium_shell_top");
    assert!(top > 0.0 && top.is_finite(), "shell top {top}");
    let frame = mf_frame { normal: vec3(glam::DVec3::Z), tangent: vec3(glam::DVec3::X) };
    let d = vec3(-glam::DVec3::Z);
    for f in [top, 0.0, -top] {
        let s = check::call(|o| unsafe { mf_medium_sigma_t(m.0, &frame, f, d, o) }).expect("sigma_t");
        check::finite_nonnegative("sigma_t", s);
        let tau = check::call(|o| unsafe { mf_medium_optical_depth(m.0, &frame, f, d, top, o) }).expect("optical depth");
        check::finite_nonnegative("optical depth", tau);
    }
    let u: [f64; MF_PHASE_SAMPLE_DIMENSIONS] = b.uniforms();
    let u = u.map(|x| if (0.0..1.0).contains(&x) { x } else { 0.5 });
    let wi = vec3(glam::DVec3::Z);
    let s = check::call(|o| unsafe { mf_phase_sample(m.0, &frame, wi, u.as_ptr(), o) }).expect("phase sample");
    if s.valid {
        let value = check::call(|o| unsafe { mf_phase_eval(m.0, &frame, wi, s.wo, o) }).expect("eval of a sample");
        let pdf = check::call(|o| unsafe { mf_phase_pdf(m.0, &frame, wi, s.wo, o) }).expect("pdf of a sample");
        check::phase_sample(&s, value, pdf);
    }
}
