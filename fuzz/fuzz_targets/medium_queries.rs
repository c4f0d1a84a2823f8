//! The medium's queries: `mf_medium_shell_top`, `_sigma_t`, `_majorant`, `_optical_depth`,
//! `_transmittance`, `_sample_free_flight` and the two flight batches, on media and arguments
//! from the fuzz input.
#![no_main]

use libfuzzer_sys::fuzz_target;
use macrofacet_ffi::*;
use macrofacet_fuzz::build;
use macrofacet_fuzz::check;
use macrofacet_fuzz::input::{dvec3, vec3, Bytes};

struct Query {
    frame: mf_frame,
    f: f64,
    f2: f64,
    d: mf_vec3,
    t: f64,
    u: f64,
}

fn query(b: &mut Bytes, scale: f64) -> Query {
    let frame = b.frame();
    Query { frame, f: b.signed_distance(scale), f2: b.signed_distance(scale), d: vec3(b.direction(dvec3(frame.normal))), t: b.length(scale), u: b.uniform_arg() }
}

fuzz_target!(|data: &[u8]| {
    let mut b = Bytes::new(data);
    let params = build::medium_params(&mut b);
    let Some(m) = build::medium(&params) else { return };
    let top = check::call(|o| unsafe { mf_medium_shell_top(m.0, o) }).expect("mf_medium_shell_top");
    assert!(top > 0.0 && top.is_finite(), "shell top {top}");
    let mut queries = Vec::new();
    for _ in 0..1 + b.below(3) {
        let q = query(&mut b, top);
        single(&m, &q);
        queries.push(q);
    }
    batches(&m, &queries);
    if b.u8() % 16 == 0 {
        nulls(&m, &queries[0]);
    }
});

fn single(m: &build::Medium, q: &Query) {
    let fr = &q.frame;
    if std::env::var_os("MF_FUZZ_DEBUG").is_some() {
        eprintln!("query: frame {:?} f {:e} f2 {:e} d {:?} t {:e} u {:e}", q.frame, q.f, q.f2, q.d, q.t, q.u);
    }
    let sigma_t = check::call(|o| unsafe { mf_medium_sigma_t(m.0, fr, q.f, q.d, o) });
    if let Ok(s) = sigma_t {
        check::not_nan_nonnegative("sigma_t", s);
    }
    if let Ok(major) = check::call(|o| unsafe { mf_medium_majorant(m.0, fr, q.f, q.f2, q.d, o) }) {
        check::not_nan_nonnegative("majorant", major);
        let s2 = check::call(|o| unsafe { mf_medium_sigma_t(m.0, fr, q.f2, q.d, o) }).expect("sigma_t where the majorant was fine");
        let s1 = sigma_t.expect("sigma_t where the majorant was fine");
        // Rounding makes ρ(f) non-monotone at the ulp scale; the majorant's margin covers it
        // (found by this target: `tests/edge_cases_medium.rs`).
        assert!(major >= s1.max(s2), "majorant {major} below sigma_t {s1} / {s2}");
    }
    let tau = check::call(|o| unsafe { mf_medium_optical_depth(m.0, fr, q.f, q.d, q.t, o) });
    if let Ok(tau) = tau {
        check::not_nan_nonnegative("optical depth", tau);
        let tr = check::call(|o| unsafe { mf_medium_transmittance(m.0, fr, q.f, q.d, q.t, o) }).expect("transmittance where tau was fine");
        check::transmittance(tr);
        assert_eq!(tr.to_bits(), (-tau).exp().to_bits(), "transmittance {tr} != exp(-{tau})");
        // A longer segment transmits less (compared as transmittances: optical depths below
        // 1e-16 are all T = 1, and f itself rounds where |f| is huge).
        let shorter = if q.u >= 0.0 && q.u < 1.0 && q.t.is_finite() { q.t * q.u } else { 0.0 };
        let tr_shorter = check::call(|o| unsafe { mf_medium_transmittance(m.0, fr, q.f, q.d, shorter, o) }).expect("shorter segment");
        assert!(tr_shorter >= tr * (1.0 - 1e-12), "T({shorter}) = {tr_shorter} < T({}) = {tr}", q.t);
    }
    if let Ok(flight) = check::call(|o| unsafe { mf_medium_sample_free_flight(m.0, fr, q.f, q.d, q.t, q.u, o) }) {
        check::free_flight(&flight, q.t);
    }
}

fn batches(m: &build::Medium, queries: &[Query]) {
    let flight: Vec<mf_flight_query> = queries.iter().map(|q| mf_flight_query { frame: q.frame, f: q.f, d: q.d, t_max: q.t, u: q.u }).collect();
    let n = flight.len();
    match check::call_array(n, |o| unsafe { mf_medium_transmittance_batch(m.0, flight.as_ptr(), n, o) }) {
        Ok(out) => {
            for (i, q) in flight.iter().enumerate() {
                let single = check::call(|o| unsafe { mf_medium_transmittance(m.0, &q.frame, q.f, q.d, q.t_max, o) }).expect("batch was fine");
                assert_eq!(out[i].to_bits(), single.to_bits(), "transmittance batch {i}");
            }
        }
        Err(_) => assert!(check::last_error().starts_with("query "), "{}", check::last_error()),
    }
    match check::call_array(n, |o| unsafe { mf_medium_sample_free_flight_batch(m.0, flight.as_ptr(), n, o) }) {
        Ok(out) => {
            for (i, q) in flight.iter().enumerate() {
                let single = check::call(|o| unsafe { mf_medium_sample_free_flight(m.0, &q.frame, q.f, q.d, q.t_max, q.u, o) }).expect("batch was fine");
                assert!(out[i].scattered == single.scattered && out[i].t.to_bits() == single.t.to_bits(), "free flight batch {i}");
                check::free_flight(&out[i], q.t_max);
            }
        }
        Err(_) => assert!(check::last_error().starts_with("query "), "{}", check::last_error()),
    }
    // An empty batch may have NULL arrays.
    check::call_array::<f64>(0, |o| unsafe { mf_medium_transmittance_batch(m.0, std::ptr::null(), 0, o) }).expect("empty batch");
}

fn nulls(m: &build::Medium, q: &Query) {
    let fr = &q.frame;
    let null_medium: *const mf_medium = std::ptr::null();
    check::null_out(|o| unsafe { mf_medium_shell_top(m.0, o) });
    check::null_out(|o| unsafe { mf_medium_sigma_t(m.0, fr, q.f, q.d, o) });
    check::null_out(|o| unsafe { mf_medium_majorant(m.0, fr, q.f, q.f2, q.d, o) });
    check::null_out(|o| unsafe { mf_medium_optical_depth(m.0, fr, q.f, q.d, q.t, o) });
    check::null_out(|o| unsafe { mf_medium_transmittance(m.0, fr, q.f, q.d, q.t, o) });
    check::null_out(|o| unsafe { mf_medium_sample_free_flight(m.0, fr, q.f, q.d, q.t, q.u, o) });
    assert!(check::call(|o| unsafe { mf_medium_sigma_t(null_medium, fr, q.f, q.d, o) }).is_err());
    assert!(check::call(|o| unsafe { mf_medium_sigma_t(m.0, std::ptr::null(), q.f, q.d, o) }).is_err());
    assert!(check::call_array::<f64>(1, |o| unsafe { mf_medium_transmittance_batch(m.0, std::ptr::null(), 1, o) }).is_err());
}
