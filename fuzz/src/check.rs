//! The property of every ABI call, checked after each one. A violation panics with the values
//! involved, which libFuzzer reports as a crash and saves as an artifact.

use crate::input::dvec3;
use glam::DVec3;
use macrofacet_ffi::{mf_collision, mf_free_flight, mf_gpis_hit, mf_last_error_message, mf_ndf_sample, mf_phase_sample_result, mf_rgb, mf_status, mf_status_str, mf_track_query, mf_vec3};
use std::ffi::CStr;
use std::mem::{size_of, MaybeUninit};

/// Byte pattern written over an out-parameter before a call; an error must leave it.
const SENTINEL: u8 = 0xA5;

/// Tolerance of unit directions (the ABI's own input check).
pub const UNIT_TOLERANCE: f64 = 1e-6;

/// Calls `f` with an out-parameter filled with [`SENTINEL`] bytes. `MF_OK`: returns the value.
/// An error: checks that the out-parameter is untouched and the error reported, returns it.
pub fn call<T: Copy>(f: impl FnOnce(*mut T) -> mf_status) -> Result<T, mf_status> {
    let mut slot = MaybeUninit::<T>::uninit();
    // SAFETY: writing bytes into our own uninitialised storage.
    unsafe { slot.as_mut_ptr().cast::<u8>().write_bytes(SENTINEL, size_of::<T>()) };
    let status = f(slot.as_mut_ptr());
    if status == mf_status::MF_OK {
        // SAFETY: MF_OK means the call wrote a whole T.
        return Ok(unsafe { slot.assume_init() });
    }
    // SAFETY: all size_of::<T>() bytes were initialised above.
    let bytes = unsafe { std::slice::from_raw_parts(slot.as_ptr().cast::<u8>(), size_of::<T>()) };
    assert!(bytes.iter().all(|b| *b == SENTINEL), "{status:?}: the out-parameter was written on failure");
    error_reported(status);
    Err(status)
}

/// [`call`] for a batch of `n` outputs: all of them untouched on an error.
pub fn call_array<T: Copy>(n: usize, f: impl FnOnce(*mut T) -> mf_status) -> Result<Vec<T>, mf_status> {
    let mut out: Vec<MaybeUninit<T>> = (0..n).map(|_| MaybeUninit::uninit()).collect();
    // SAFETY: our own storage of n elements.
    unsafe { out.as_mut_ptr().cast::<u8>().write_bytes(SENTINEL, n * size_of::<T>()) };
    let ptr = if n == 0 { std::ptr::null_mut() } else { out.as_mut_ptr().cast::<T>() };
    let status = f(ptr);
    if status == mf_status::MF_OK {
        // SAFETY: MF_OK means the call wrote all n elements.
        return Ok(out.into_iter().map(|x| unsafe { x.assume_init() }).collect());
    }
    // SAFETY: every byte was initialised above.
    let bytes = unsafe { std::slice::from_raw_parts(out.as_ptr().cast::<u8>(), n * size_of::<T>()) };
    assert!(bytes.iter().all(|b| *b == SENTINEL), "{status:?}: a batch output was written on failure");
    error_reported(status);
    Err(status)
}

/// A call without out-parameters: an error must be reported.
pub fn status(status: mf_status) -> Result<(), mf_status> {
    if status == mf_status::MF_OK {
        Ok(())
    } else {
        error_reported(status);
        Err(status)
    }
}

/// A NULL out-parameter: the call must say so and write nothing.
pub fn null_out<T>(f: impl FnOnce(*mut T) -> mf_status) {
    let status = f(std::ptr::null_mut());
    assert!(status != mf_status::MF_OK, "a NULL out-parameter was accepted");
    error_reported(status);
}

/// The last error message of this thread.
pub fn last_error() -> String {
    let mut len = 0usize;
    // SAFETY: len 0 with a NULL buffer queries the length.
    assert_eq!(unsafe { mf_last_error_message(std::ptr::null_mut(), 0, &mut len) }, mf_status::MF_OK);
    let mut buf = vec![0u8; len + 1];
    let mut len2 = 0usize;
    // SAFETY: buf holds len + 1 bytes.
    assert_eq!(unsafe { mf_last_error_message(buf.as_mut_ptr().cast(), buf.len(), &mut len2) }, mf_status::MF_OK);
    assert_eq!(len, len2, "the message length changed between two queries");
    assert_eq!(buf[len], 0, "the message is not NUL-terminated");
    String::from_utf8(buf[..len].to_vec()).expect("the message is UTF-8")
}

/// An error status: in 7100–7199, described by `mf_status_str`, with a message.
fn error_reported(status: mf_status) {
    let code = status as i32;
    assert!((7100..=7199).contains(&code), "status {code} outside the error range");
    // SAFETY: mf_status_str returns a static NUL-terminated string.
    let text = unsafe { CStr::from_ptr(mf_status_str(code)) }.to_str().unwrap();
    assert!(!text.is_empty() && text != "unknown status", "status {code} has no description");
    let message = last_error();
    assert!(!message.is_empty(), "{status:?} without a message");
    assert!(code != mf_status::MF_ERROR_INTERNAL as i32, "internal error (a caught panic): {message}");
}

/// Neither NaN nor negative (`+inf` allowed: an extinction or optical depth may overflow at
/// `|f|` or `t` near the top of the range, the IEEE-correct answer).
pub fn not_nan_nonnegative(what: &str, x: f64) {
    assert!(x >= 0.0, "{what} = {x}");
}

pub fn finite_nonnegative(what: &str, x: f64) {
    assert!(x >= 0.0 && x.is_finite(), "{what} = {x}");
}

pub fn unit(what: &str, v: mf_vec3) {
    let v = dvec3(v);
    assert!(v.is_finite() && (v.length() - 1.0).abs() <= UNIT_TOLERANCE, "{what} = {v}, length {}", v.length());
}

pub fn transmittance(t: f64) {
    assert!((0.0..=1.0).contains(&t), "transmittance {t}");
}

/// Where a call that passed (or a transmittance) ended: at `t_max`, or with an exit level
/// anywhere on `[0, t_max]`.
pub fn ended(t: f64, q: &mf_track_query) {
    if q.exit_level == 0.0 {
        assert!(t.to_bits() == q.t_max.to_bits(), "ended at t = {t} != t_max = {}", q.t_max);
    } else {
        assert!(t >= 0.0 && t <= q.t_max, "ended at t = {t} outside [0, {}] (exit level {})", q.t_max, q.exit_level);
    }
}

/// A sampled free flight on `[0, t_max]`: scattered at a finite `0 <= t <= t_max`, or passed
/// with `t = t_max`.
pub fn free_flight(flight: &mf_free_flight, t_max: f64) {
    if flight.scattered {
        assert!(flight.t >= 0.0 && flight.t <= t_max && flight.t.is_finite(), "scattered at t = {} on [0, {t_max}]", flight.t);
    } else {
        assert!(flight.t.to_bits() == t_max.to_bits(), "passed with t = {} != t_max = {t_max}", flight.t);
    }
}

pub fn rgb(what: &str, c: mf_rgb) {
    for x in [c.r, c.g, c.b] {
        finite_nonnegative(what, x);
    }
}

/// `|a - b| <= rel * max(|a|, |b|)`.
pub fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs())
}

/// A phase sample: invalid ones are all zeros; valid ones have a unit `wo`, `pdf > 0` equal to
/// `pdf_at_wo` (what `mf_phase_pdf` says for the returned `wo`), and `weight = value / pdf`
/// with `value` = `mf_phase_eval` there (relative 1e-6).
pub fn phase_sample(s: &mf_phase_sample_result, value_at_wo: mf_rgb, pdf_at_wo: f64) {
    if !s.valid {
        let zero = [s.wo.x, s.wo.y, s.wo.z, s.weight.r, s.weight.g, s.weight.b, s.pdf].iter().all(|x| *x == 0.0);
        assert!(zero, "an invalid sample must be all zeros: {s:?}");
        return;
    }
    unit("sample wo", s.wo);
    assert!(s.pdf > 0.0 && s.pdf.is_finite(), "valid sample with pdf {}", s.pdf);
    assert!(s.pdf.to_bits() == pdf_at_wo.to_bits(), "sample pdf {} but mf_phase_pdf {pdf_at_wo}", s.pdf);
    rgb("sample weight", s.weight);
    for (w, v) in [(s.weight.r, value_at_wo.r), (s.weight.g, value_at_wo.g), (s.weight.b, value_at_wo.b)] {
        if v < f64::MIN_POSITIVE {
            // eval underflowed (e.g. a reflectance of 1e-206 times a density of 1e-212): then so
            // must weight * pdf.
            assert!(w * s.pdf <= 2.0 * f64::MIN_POSITIVE, "weight {w} but eval {v} (pdf {})", s.pdf);
        } else if w.abs().max(v / s.pdf) >= 1e-290 {
            // (Below that both came through subnormal arithmetic and carry no relative precision.)
            assert!(close(w, v / s.pdf, 1e-6), "weight {w} but eval/pdf = {v}/{} = {}", s.pdf, v / s.pdf);
        }
    }
}

/// `p` is `o + t d` to 1e-12 of `|o| + t`. In max norms: a Euclidean length squares the
/// coordinates, which overflows near 1e308 (found by fuzzing: a collision point one ulp off at
/// 1.2e308 failed as an infinite distance).
fn on_ray(p: DVec3, o: DVec3, d: DVec3, t: f64) -> bool {
    let max_norm = |v: DVec3| v.abs().max_element();
    max_norm(p - (o + t * d)) <= 1e-12 * (max_norm(o) + t).max(f64::MIN_POSITIVE)
}

/// A gpis hit on `origin + t d`, `0 < t <= t_max`: finite, on the ray, outward unit normal
/// facing the ray; a miss is all zeros.
pub fn gpis_hit(h: &mf_gpis_hit, origin: mf_vec3, d: mf_vec3, t_max: f64) {
    if !h.hit {
        let zero = [h.t, h.point.x, h.point.y, h.point.z, h.normal.x, h.normal.y, h.normal.z, h.gradient.x, h.gradient.y, h.gradient.z]
            .iter()
            .all(|x| *x == 0.0);
        assert!(zero, "a miss must be all zeros: {h:?}");
        return;
    }
    assert!(h.t > 0.0 && h.t <= t_max && h.t.is_finite(), "hit at t = {} on (0, {t_max}]", h.t);
    let (o, d, p) = (dvec3(origin), dvec3(d).normalize(), dvec3(h.point));
    assert!(p.is_finite() && dvec3(h.gradient).is_finite(), "{h:?}");
    assert!(on_ray(p, o, d, h.t), "hit point {p} is not o + t d = {}", o + h.t * d);
    unit("hit normal", h.normal);
    // (To rounding: a grazing crossing has n.d ~ 1e-17 of either sign.)
    assert!(dvec3(h.normal).dot(d) <= 1e-12, "the normal must face the ray: n.d = {}", dvec3(h.normal).dot(d));
}

/// A tracked free flight of `q` (`mf_track_free_flight`): a collision at a finite
/// `0 <= t <= t_max` at `p = origin + t d` with `f` not NaN and a frame the phase calls take
/// (unit normal, finite tangent); or a pass with `t = t_max` and the rest zero.
pub fn collision(c: &mf_collision, q: &mf_track_query) {
    if !c.scattered {
        let zero = [c.p.x, c.p.y, c.p.z, c.f, c.frame.normal.x, c.frame.normal.y, c.frame.normal.z, c.frame.tangent.x, c.frame.tangent.y, c.frame.tangent.z]
            .iter()
            .all(|x| *x == 0.0);
        assert!(zero && c.local.set == 0, "a pass must have zero point, f, frame and local: {c:?}");
        ended(c.t, q);
        return;
    }
    assert!(c.t >= 0.0 && c.t <= q.t_max && c.t.is_finite(), "collision at t = {} on [0, {}]", c.t, q.t_max);
    let (o, d, p) = (dvec3(q.origin), dvec3(q.d).normalize(), dvec3(c.p));
    // (f as the surface answered it: a host may answer ±inf, which the tracker takes.)
    assert!(p.is_finite() && !c.f.is_nan(), "collision point {p}, f = {}", c.f);
    assert!(on_ray(p, o, d, c.t), "collision point {p} is not o + t d = {}", o + c.t * d);
    unit("collision frame normal", c.frame.normal);
    assert!(dvec3(c.frame.tangent).is_finite(), "collision frame tangent {:?}", c.frame.tangent);
}

/// A visible-normal sample (`mf_ndf_sample_visible`): invalid ones are all zeros; valid ones
/// have a unit `m` and `pdf > 0` equal to `pdf_at_m` (what `mf_ndf_pdf_visible` says at `m`)
/// to `rel` (the rounding of `m`'s trip through world space, which a grazing `wi` amplifies).
pub fn ndf_sample(s: &mf_ndf_sample, pdf_at_m: f64, rel: f64) {
    if !s.valid {
        assert!([s.m.x, s.m.y, s.m.z, s.pdf].iter().all(|x| *x == 0.0), "an invalid sample must be all zeros: {s:?}");
        return;
    }
    unit("sample m", s.m);
    assert!(s.pdf > 0.0 && s.pdf.is_finite(), "valid sample with pdf {}", s.pdf);
    assert!(close(s.pdf, pdf_at_m, rel), "sample pdf {} but mf_ndf_pdf_visible {pdf_at_m}", s.pdf);
}
