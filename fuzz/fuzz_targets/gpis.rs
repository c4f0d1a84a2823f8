//! The realization-based ground truth: `mf_gpis_envelope`, `mf_gpis_trace` with mean surfaces
//! from the fuzz input (planes, spheres, constants, callbacks that turn NaN or infinite after a
//! number of calls) and both kinds of start, and `mf_gpis_scatter` at the crossings.
#![no_main]

use glam::DVec3;
use libfuzzer_sys::fuzz_target;
use macrofacet_ffi::*;
use macrofacet_fuzz::build;
use macrofacet_fuzz::check;
use macrofacet_fuzz::input::{dvec3, vec3, Bytes};
use std::ffi::c_void;
use std::ptr;

/// Most callback calls a trace may make from the first non-finite answer on (README).
const CALLS_AFTER_NAN: usize = 5;

#[derive(Clone, Copy, Debug)]
enum Shape {
    Plane { normal: DVec3, offset: f64 },
    Sphere { center: DVec3, radius: f64 },
    /// Not a signed distance at all.
    Constant { f: f64, gradient: DVec3 },
}

/// The host's mean surface: a shape that answers `bad` (NaN or infinite) from call `good + 1` on.
struct Sdf {
    shape: Shape,
    good: usize,
    bad: f64,
    calls: usize,
}

unsafe extern "C" fn sdf(user_data: *mut c_void, p: mf_vec3, out: *mut mf_sdf_sample) {
    let s = &mut *(user_data as *mut Sdf);
    s.calls += 1;
    let p = dvec3(p);
    let (mut f, mut g) = match s.shape {
        Shape::Plane { normal, offset } => (normal.dot(p) - offset, normal),
        Shape::Sphere { center, radius } => ((p - center).length() - radius, (p - center).try_normalize().unwrap_or(DVec3::Z)),
        Shape::Constant { f, gradient } => (f, gradient),
    };
    if s.calls > s.good {
        if s.calls % 2 == 0 {
            f = s.bad;
        } else {
            g.y = s.bad;
        }
    }
    *out = mf_sdf_sample { f, gradient: vec3(g), u: 0.0, v: 0.0 };
}

fuzz_target!(|data: &[u8]| {
    let mut b = Bytes::new(data);
    let Some(g) = build::gpis(&build::gpis_params(&mut b)) else { return };
    let envelope = check::call(|o| unsafe { mf_gpis_envelope(g.0, ptr::null(), o) }).expect("mf_gpis_envelope");
    assert!(envelope > 0.0 && envelope.is_finite(), "envelope {envelope}");
    let shape = match b.u8() % 8 {
        0 => Shape::Sphere { center: b.sphere() * envelope * 10.0 * b.unit(), radius: envelope * b.log_uniform(-1.0, 3.0) },
        1 => Shape::Constant { f: b.signed_distance(envelope), gradient: DVec3::new(b.float(), b.float(), b.float()) },
        _ => Shape::Plane { normal: b.sphere(), offset: envelope * (2.0 * b.unit() - 1.0) },
    };
    let good = if b.u8() % 4 == 0 { b.below(40) } else { usize::MAX };
    let bad = b.choose(&[f64::NAN, f64::INFINITY, f64::NEG_INFINITY]);
    let mut state = Sdf { shape, good, bad, calls: 0 };
    let user_data = &mut state as *mut Sdf as *mut c_void;

    let origin = b.sphere() * envelope * b.log_uniform(-3.0, 2.0);
    let d = vec3(b.direction(-origin));
    // A mean that is no signed distance can keep the march going until it takes its cap of 1e5
    // samples (~0.1 s, seconds under the sanitizer): such segments are kept short.
    let t_max = match shape {
        Shape::Constant { .. } => b.length(envelope).min(8.0 * envelope),
        _ if b.u8() % 16 == 0 => f64::INFINITY,
        _ => b.length(envelope).min(64.0 * envelope),
    };
    let start = if b.u8() % 4 == 0 {
        mf_gpis_start { kind: b.choose(&[MF_GPIS_START_ON_SURFACE, 7]), gradient: vec3(DVec3::new(b.float(), b.float(), b.float())) }
    } else {
        mf_gpis_start { kind: MF_GPIS_START_FREE, gradient: vec3(DVec3::ZERO) }
    };
    let seed = b.u64();
    let Some(hit) = trace(&g, &mut state, user_data, origin, d, t_max, start, seed) else { return };
    if !hit.hit {
        return;
    }
    // Reflect at the crossing and leave from it (the host's next segment), or shoot a shadow
    // ray from it in any direction.
    let wi = vec3(-dvec3(d).normalize());
    let next = match check::call(|o| unsafe { mf_gpis_scatter(g.0, &hit.local, wi, hit.normal, o) }) {
        Ok(s) if s.valid => {
            check::unit("scattered wo", s.wo);
            // wo·n = wi·n > 0 up to rounding, which a grazing wi (wi·n ~ 1e-17) can push below 0.
            assert!(s.pdf == 0.0 && dvec3(s.wo).dot(dvec3(hit.normal)) > -1e-15, "scatter {s:?} at normal {:?}", hit.normal);
            check::rgb("scatter weight", s.weight);
            assert!(s.weight.r <= 1.0 && s.weight.g <= 1.0 && s.weight.b <= 1.0, "scatter weight {:?}", s.weight);
            if b.bool() { dvec3(s.wo) } else { b.direction(dvec3(hit.normal)) }
        }
        Ok(s) => {
            check::phase_sample(&s, mf_rgb { r: 0.0, g: 0.0, b: 0.0 }, 0.0);
            return;
        }
        Err(_) => return,
    };
    let start = mf_gpis_start { kind: MF_GPIS_START_ON_SURFACE, gradient: hit.gradient };
    trace(&g, &mut state, user_data, dvec3(hit.point), vec3(next), t_max, start, seed ^ 1);
});

/// One trace with the property checked: a hit on `(0, t_max]`, or a miss, or — when the callback
/// answered a non-finite value — `MF_ERROR_INVALID_ARGUMENT` within [`CALLS_AFTER_NAN`] calls.
#[allow(clippy::too_many_arguments)]
fn trace(
    g: &build::Gpis,
    state: &mut Sdf,
    user_data: *mut c_void,
    origin: DVec3,
    d: mf_vec3,
    t_max: f64,
    start: mf_gpis_start,
    seed: u64,
) -> Option<mf_gpis_hit> {
    state.calls = 0;
    if std::env::var_os("MF_FUZZ_DEBUG").is_some() {
        eprintln!("trace: shape {:?} good {} origin {origin:?} d {d:?} t_max {t_max:e} start {start:?} seed {seed}", state.shape, state.good);
    }
    let result = check::call(|o| unsafe { mf_gpis_trace(g.0, Some(sdf), ptr::null(), user_data, vec3(origin), d, t_max, &start, seed, o) });
    if state.calls > state.good {
        assert_eq!(result.err(), Some(mf_status::MF_ERROR_INVALID_ARGUMENT), "a non-finite mean must fail the trace");
        assert!(state.calls - state.good <= CALLS_AFTER_NAN, "{} callback calls after the first non-finite answer", state.calls - state.good);
        return None;
    }
    let hit = result.ok()?;
    check::gpis_hit(&hit, vec3(origin), d, t_max);
    Some(hit)
}
