//! The phase function: `mf_phase_eval`, `mf_phase_pdf`, `mf_phase_sample` and their batches, on
//! media, frames, directions and random numbers from the fuzz input.
#![no_main]

use libfuzzer_sys::fuzz_target;
use macrofacet_ffi::*;
use macrofacet_fuzz::build;
use macrofacet_fuzz::check;
use macrofacet_fuzz::input::{dvec3, vec3, Bytes};

struct Query {
    frame: mf_frame,
    wi: mf_vec3,
    wo: mf_vec3,
    u: [f64; MF_PHASE_SAMPLE_DIMENSIONS],
}

fuzz_target!(|data: &[u8]| {
    let mut b = Bytes::new(data);
    let Some(m) = build::medium(&build::medium_params(&mut b)) else { return };
    let mut queries = Vec::new();
    for _ in 0..1 + b.below(2) {
        let frame = b.frame();
        let n = dvec3(frame.normal);
        let q = Query { frame, wi: vec3(b.direction(n)), wo: vec3(b.direction(n)), u: b.uniforms() };
        if std::env::var_os("MF_FUZZ_DEBUG").is_some() {
            eprintln!("query: frame {:?} wi {:?} wo {:?} u {:?}", q.frame, q.wi, q.wo, q.u);
        }
        single(&m, &q);
        queries.push(q);
    }
    batches(&m, &queries);
    if b.u8() % 16 == 0 {
        let q = &queries[0];
        check::null_out(|o| unsafe { mf_phase_eval(m.0, &q.frame, q.wi, q.wo, o) });
        check::null_out(|o| unsafe { mf_phase_pdf(m.0, &q.frame, q.wi, q.wo, o) });
        check::null_out(|o| unsafe { mf_phase_sample(m.0, &q.frame, q.wi, q.u.as_ptr(), o) });
        assert!(check::call(|o| unsafe { mf_phase_sample(m.0, &q.frame, q.wi, std::ptr::null(), o) }).is_err());
        assert!(check::call(|o| unsafe { mf_phase_eval(std::ptr::null(), &q.frame, q.wi, q.wo, o) }).is_err());
    }
});

/// `eval` and `pdf` at (wi, wo), then a sample and `eval`/`pdf` at its `wo`.
fn single(m: &build::Medium, q: &Query) {
    let fr = &q.frame;
    let value = check::call(|o| unsafe { mf_phase_eval(m.0, fr, q.wi, q.wo, o) });
    let pdf = check::call(|o| unsafe { mf_phase_pdf(m.0, fr, q.wi, q.wo, o) });
    assert_eq!(value.is_ok(), pdf.is_ok(), "eval and pdf validate the same arguments");
    if let (Ok(value), Ok(pdf)) = (value, pdf) {
        check::rgb("eval", value);
        // +inf allowed: the Eq. 40 mixture's density diverges like 1/(wi·m) as wo turns back
        // onto -wi, and overflows within ~1e-308 of it (the IEEE-correct answer).
        check::not_nan_nonnegative("pdf", pdf);
        // A direction the phase function reaches is one the sampler reaches (MIS needs it).
        assert!(pdf > 0.0 || [value.r, value.g, value.b].iter().all(|v| *v == 0.0), "eval {value:?} with pdf 0");
    }
    if let Ok(s) = check::call(|o| unsafe { mf_phase_sample(m.0, fr, q.wi, q.u.as_ptr(), o) }) {
        let (mut value, mut pdf) = (mf_rgb { r: 0.0, g: 0.0, b: 0.0 }, 0.0);
        if s.valid {
            value = check::call(|o| unsafe { mf_phase_eval(m.0, fr, q.wi, s.wo, o) }).expect("eval of a sampled direction");
            pdf = check::call(|o| unsafe { mf_phase_pdf(m.0, fr, q.wi, s.wo, o) }).expect("pdf of a sampled direction");
        }
        check::phase_sample(&s, value, pdf);
    }
}

/// Batches equal the single calls bit for bit, or fail naming a query and writing nothing.
fn batches(m: &build::Medium, queries: &[Query]) {
    let n = queries.len();
    let pq: Vec<mf_phase_query> = queries.iter().map(|q| mf_phase_query { frame: q.frame, wi: q.wi, wo: q.wo }).collect();
    match check::call_array(n, |o| unsafe { mf_phase_eval_batch(m.0, pq.as_ptr(), n, o) }) {
        Ok(out) => {
            for (i, q) in pq.iter().enumerate() {
                let value = check::call(|o| unsafe { mf_phase_eval(m.0, &q.frame, q.wi, q.wo, o) }).expect("batch was fine");
                let pdf = check::call(|o| unsafe { mf_phase_pdf(m.0, &q.frame, q.wi, q.wo, o) }).expect("batch was fine");
                assert!(same_rgb(out[i].value, value) && out[i].pdf.to_bits() == pdf.to_bits(), "eval batch {i}");
            }
        }
        Err(_) => assert!(check::last_error().starts_with("query "), "{}", check::last_error()),
    }
    let sq: Vec<mf_phase_sample_query> = queries.iter().map(|q| mf_phase_sample_query { frame: q.frame, wi: q.wi, u: q.u }).collect();
    match check::call_array(n, |o| unsafe { mf_phase_sample_batch(m.0, sq.as_ptr(), n, o) }) {
        Ok(out) => {
            for (i, q) in sq.iter().enumerate() {
                let s = check::call(|o| unsafe { mf_phase_sample(m.0, &q.frame, q.wi, q.u.as_ptr(), o) }).expect("batch was fine");
                let same = out[i].valid == s.valid
                    && same_rgb(out[i].weight, s.weight)
                    && out[i].pdf.to_bits() == s.pdf.to_bits()
                    && [out[i].wo.x, out[i].wo.y, out[i].wo.z].map(f64::to_bits) == [s.wo.x, s.wo.y, s.wo.z].map(f64::to_bits);
                assert!(same, "sample batch {i}: {:?} vs {s:?}", out[i]);
            }
        }
        Err(_) => assert!(check::last_error().starts_with("query "), "{}", check::last_error()),
    }
}

fn same_rgb(a: mf_rgb, b: mf_rgb) -> bool {
    [a.r, a.g, a.b].map(f64::to_bits) == [b.r, b.g, b.b].map(f64::to_bits)
}
