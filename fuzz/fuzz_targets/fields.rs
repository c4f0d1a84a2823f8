//! Spatially varying media: `mf_field_new_callbacks` / `mf_field_free`, the tracking calls with a
//! field whose callbacks answer within or outside the bounds they declare, NaN, out-of-domain
//! values or failure codes after a number of calls (`fuzz/src/host.rs`), and the phase function
//! at the collisions' local parameters: `mf_phase_sample_local`, `mf_phase_eval_pdf_local`
//! (and `mf_phase_eval_pdf`), with the phase target's property, and with any local parameters.
#![no_main]

use glam::DVec3;
use libfuzzer_sys::fuzz_target;
use macrofacet_ffi::*;
use macrofacet_fuzz::build::{self, Value};
use macrofacet_fuzz::check;
use macrofacet_fuzz::host::{FieldHost, Host};
use macrofacet_fuzz::input::{dvec3, vec3, Bytes};
use macrofacet_fuzz::surface;
use macrofacet_fuzz::track::{Field, Scene};
use std::ptr;

fuzz_target!(|data: &[u8]| {
    let mut b = Bytes::new(data);
    let params = build::medium_params(&mut b);
    let Some(medium) = build::medium(&params) else { return };
    let sigma = build::sigma(&params).expect("an accepted medium has a sigma");
    let gpss = !params.iter().any(|p| &p.name[..] == b"distribution" && matches!(&p.value, Value::String(s) if &s[..] != b"gpss"));
    let top = check::call(|o| unsafe { mf_medium_shell_top(medium.0, o) }).expect("mf_medium_shell_top");
    // The surface's size: a tenth of a shell height to 1e4 of them.
    let size = top * b.log_uniform(-1.0, 4.0);
    let field_host = FieldHost::draw(&mut b, sigma, gpss, size);
    let mut callbacks = field_host.callbacks();
    match b.u8() % 32 {
        0 => callbacks.at = None,
        1 => callbacks.bounds = None,
        2 => callbacks.sigma_max = b.float(),
        _ => {}
    }
    if std::env::var_os("MF_FUZZ_DEBUG").is_some() {
        eprintln!("field: {field_host:?} {callbacks:?}");
    }
    let Ok(field) = check::call(|o| unsafe { mf_field_new_callbacks(&callbacks, o) }) else { return };
    let field = Field(field);
    let Some(built) = surface::surface(&mut b, size, DVec3::ZERO) else { return };
    let mut scene = Scene { medium: &medium, surface: &built.surface, field: Some(&field), host: Host { surface: built.host, field: Some(field_host), surface_exact: built.exact }, center: DVec3::ZERO, size };
    let mut queries = Vec::new();
    for _ in 0..1 + b.below(2) {
        let q = scene.query(&mut b);
        if let Some(c) = scene.free_flight(&q) {
            if c.scattered {
                // The collision's parameters and frame are what the _local calls take.
                let wi = vec3(-dvec3(q.d).normalize());
                let u: [f64; MF_PHASE_SAMPLE_DIMENSIONS] = std::array::from_fn(|_| b.unit());
                phase_local(&medium, &c.local, &c.frame, wi, b.direction(dvec3(c.frame.normal)), &u, true);
            }
        }
        scene.transmittance(&q);
        queries.push(q);
    }
    scene.batches(&queries);
    // Any local parameters, frame and directions.
    let local = local_params(&mut b);
    let frame = b.frame();
    let n = dvec3(frame.normal);
    let (wi, wo, u) = (vec3(b.direction(n)), b.direction(n), b.uniforms());
    phase_local(&medium, &local, &frame, wi, wo, &u, false);
    // NULL local parameters: the medium's own, bit for bit.
    let s = check::call(|o| unsafe { mf_phase_sample_local(medium.0, ptr::null(), &frame, wi, u.as_ptr(), o) });
    let s0 = check::call(|o| unsafe { mf_phase_sample(medium.0, &frame, wi, u.as_ptr(), o) });
    assert_eq!(format!("{s:?}"), format!("{s0:?}"), "mf_phase_sample_local(NULL) vs mf_phase_sample");
    let v = check::call(|o| unsafe { mf_phase_eval_pdf_local(medium.0, ptr::null(), &frame, wi, vec3(wo), o) });
    let v0 = check::call(|o| unsafe { mf_phase_eval_pdf(medium.0, &frame, wi, vec3(wo), o) });
    assert_eq!(format!("{v:?}"), format!("{v0:?}"), "mf_phase_eval_pdf_local(NULL) vs mf_phase_eval_pdf");
    // mf_phase_eval_pdf is mf_phase_eval and mf_phase_pdf in one call.
    let value = check::call(|o| unsafe { mf_phase_eval(medium.0, &frame, wi, vec3(wo), o) });
    let pdf = check::call(|o| unsafe { mf_phase_pdf(medium.0, &frame, wi, vec3(wo), o) });
    match v0 {
        Ok(v0) => assert_eq!(format!("{:?}", (v0.value, v0.pdf)), format!("{:?}", (value.expect("eval"), pdf.expect("pdf"))), "mf_phase_eval_pdf vs eval, pdf"),
        Err(_) => assert!(value.is_err() && pdf.is_err(), "mf_phase_eval_pdf refused what eval/pdf took"),
    }
    if b.u8() % 16 == 0 {
        check::null_out(|o| unsafe { mf_field_new_callbacks(&callbacks, o) });
        assert!(check::call(|o| unsafe { mf_field_new_callbacks(ptr::null(), o) }).is_err());
        check::null_out(|o| unsafe { mf_phase_sample_local(medium.0, &local, &frame, wi, u.as_ptr(), o) });
        check::null_out(|o| unsafe { mf_phase_eval_pdf_local(medium.0, &local, &frame, wi, vec3(wo), o) });
        check::null_out(|o| unsafe { mf_phase_eval_pdf(medium.0, &frame, wi, vec3(wo), o) });
        assert!(check::call(|o| unsafe { mf_phase_sample_local(medium.0, &local, &frame, wi, ptr::null(), o) }).is_err());
        assert!(check::call(|o| unsafe { mf_phase_eval_pdf_local(ptr::null(), &local, &frame, wi, vec3(wo), o) }).is_err());
    }
});

/// Any local parameters: each field set or not, values in or outside their domain.
fn local_params(b: &mut Bytes) -> mf_local_params {
    let mut p = mf_local_params::NONE;
    p.set = if b.u8() % 16 == 0 { b.u32() } else { b.u8() as u32 & 15 };
    p.sigma = b.positive(-50.0, 50.0);
    p.alpha = vec3(DVec3::new(b.positive(-6.0, 3.0), b.positive(-6.0, 3.0), if b.bool() { 0.0 } else { b.positive(-6.0, 3.0) }));
    for a in &mut p.anisotropy[..3] {
        *a = b.positive(-6.0, 6.0);
    }
    for a in &mut p.anisotropy[3..] {
        *a = if b.u8() % 4 == 0 { b.signed_distance(1.0) } else { 0.0 };
    }
    let r = if b.u8() % 8 == 0 { b.float() } else { b.unit() };
    p.reflectance_scale = mf_rgb { r, g: b.unit(), b: r };
    p
}

/// `mf_phase_eval_pdf_local` at (wi, wo) and a sample with its eval/pdf, with the phase target's
/// property (`check::phase_sample`). `accepted`: the local parameters and frame came from a
/// collision, and `wi`, `u` are valid: the calls must succeed.
fn phase_local(medium: &build::Medium, local: &mf_local_params, frame: &mf_frame, wi: mf_vec3, wo: DVec3, u: &[f64; MF_PHASE_SAMPLE_DIMENSIONS], accepted: bool) {
    if std::env::var_os("MF_FUZZ_DEBUG").is_some() {
        eprintln!("phase local: {local:?} frame {frame:?} wi {wi:?} wo {wo} u {u:?}");
    }
    if let Ok(v) = check::call(|o| unsafe { mf_phase_eval_pdf_local(medium.0, local, frame, wi, vec3(wo), o) }) {
        check::rgb("eval", v.value);
        check::not_nan_nonnegative("pdf", v.pdf);
        assert!(v.pdf > 0.0 || [v.value.r, v.value.g, v.value.b].iter().all(|x| *x == 0.0), "eval {:?} with pdf 0", v.value);
    }
    let sample = check::call(|o| unsafe { mf_phase_sample_local(medium.0, local, frame, wi, u.as_ptr(), o) });
    if accepted {
        assert!(sample.is_ok(), "a collision's local parameters and frame were refused: {}", check::last_error());
    }
    if let Ok(s) = sample {
        let (mut value, mut pdf) = (mf_rgb { r: 0.0, g: 0.0, b: 0.0 }, 0.0);
        if s.valid {
            let v = check::call(|o| unsafe { mf_phase_eval_pdf_local(medium.0, local, frame, wi, s.wo, o) }).expect("eval of a sampled direction");
            (value, pdf) = (v.value, v.pdf);
        }
        check::phase_sample(&s, value, pdf);
    }
}
