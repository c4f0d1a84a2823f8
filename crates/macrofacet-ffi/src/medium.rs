//! `mf_medium`: the macrofacet medium and its phase function, for a host's path tracer.
//!
//! Every query takes the event's local frame ([`mf_frame`]: the geometric normal, i.e. the
//! gradient of the mean signed distance, and a tangent for anisotropic roughness) and world-space
//! directions. Random numbers come from the host: the library owns no generator.

use super::{arg, boundary, free_handle, into_handle, mf_params, mf_status, out, FfiError, FfiResult};
use macrofacet::error::{Error, ErrorKind};
use macrofacet::frame::{not_a_direction, unit_direction, Frame};
use macrofacet::medium::{FreeFlight, MacrofacetMedium};
use macrofacet::params::medium_from_params;
use macrofacet::phase::PHASE_SAMPLE_DIMENSIONS;
use macrofacet::tracking::ProjectedAreaBounds;
use glam::DVec3;

/// Uniform numbers consumed by [`mf_phase_sample`].
pub const MF_PHASE_SAMPLE_DIMENSIONS: usize = 5;
const _: () = assert!(MF_PHASE_SAMPLE_DIMENSIONS == PHASE_SAMPLE_DIMENSIONS);

/// A 3-vector of doubles.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct mf_vec3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

/// Linear RGB.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct mf_rgb {
    pub r: f64,
    pub g: f64,
    pub b: f64,
}

/// The local frame of an event: `normal` = gradient of the mean SDF (need not be normalised,
/// must be non-zero), `tangent` = direction of `alpha_u` (projected orthogonal to the normal; any
/// vector, even zero, for isotropic roughness).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct mf_frame {
    pub normal: mf_vec3,
    pub tangent: mf_vec3,
}

/// Result of free-flight sampling: `scattered` is true when a collision happened at distance `t`
/// (then `0 <= t <= t_max`); false when the ray passed the whole segment (`t` is then `t_max`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct mf_free_flight {
    pub scattered: bool,
    pub t: f64,
}

/// A sampled scattering direction. `valid` is false when nothing can be sampled (no flake visible
/// from `wi`); the other fields are then zero.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct mf_phase_sample_result {
    /// New propagation direction, world space, pointing away from the event.
    pub wo: mf_vec3,
    /// `p(wi, wo) / pdf`: the throughput factor (includes the flakes' reflectance).
    pub weight: mf_rgb,
    /// Solid-angle density of `wo`.
    pub pdf: f64,
    pub valid: bool,
}

/// One free-flight or transmittance query of a batch: the segment starts where the signed
/// distance is `f`, runs along the unit propagation direction `d` for `t_max` (may be +inf);
/// `u` in [0, 1) drives sampling (ignored by transmittance).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct mf_flight_query {
    pub frame: mf_frame,
    pub f: f64,
    pub d: mf_vec3,
    pub t_max: f64,
    pub u: f64,
}

/// One phase-function evaluation of a batch (`wi`, `wo` point away from the event).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct mf_phase_query {
    pub frame: mf_frame,
    pub wi: mf_vec3,
    pub wo: mf_vec3,
}

/// The phase function's value and sampling density for one pair of directions.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct mf_phase_value {
    pub value: mf_rgb,
    pub pdf: f64,
}

/// One phase-function sample of a batch.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct mf_phase_sample_query {
    pub frame: mf_frame,
    pub wi: mf_vec3,
    pub u: [f64; MF_PHASE_SAMPLE_DIMENSIONS],
}

/// An immutable macrofacet medium. Safe to share between threads.
pub struct mf_medium {
    pub(crate) inner: MacrofacetMedium,
    /// Built once for the tracking calls (`ProjectedAreaBounds::of`, 88 KiB).
    pub(crate) bounds: ProjectedAreaBounds,
}

impl From<mf_vec3> for DVec3 {
    fn from(v: mf_vec3) -> DVec3 {
        DVec3::new(v.x, v.y, v.z)
    }
}

impl From<DVec3> for mf_vec3 {
    fn from(v: DVec3) -> mf_vec3 {
        mf_vec3 { x: v.x, y: v.y, z: v.z }
    }
}

pub(crate) fn rgb(c: [f64; 3]) -> mf_rgb {
    mf_rgb { r: c[0], g: c[1], b: c[2] }
}

fn invalid(message: String) -> FfiError {
    Error::new(ErrorKind::InvalidArgument, message).into()
}

pub(crate) fn frame(f: &mf_frame) -> FfiResult<Frame> {
    Ok(Frame::from_normal_tangent(f.normal.into(), f.tangent.into())?)
}

/// A world-space unit direction, in the local frame.
pub(crate) fn local_direction(frame: &Frame, name: &str, v: mf_vec3) -> FfiResult<DVec3> {
    match unit_direction(v.into()) {
        Some(d) => Ok(frame.to_local(d)),
        None => Err(not_a_direction(name, v.into()).into()),
    }
}

fn finite(name: &str, x: f64) -> FfiResult<f64> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(invalid(format!("{name} must be finite, got {x}")))
    }
}

/// A length: `>= 0`, `+inf` allowed ("to infinity").
fn length(name: &str, t: f64) -> FfiResult<f64> {
    if t >= 0.0 {
        Ok(t)
    } else {
        Err(invalid(format!("{name} must be >= 0 (or +inf), got {t}")))
    }
}

pub(super) fn uniform(name: impl std::fmt::Display, u: f64) -> FfiResult<f64> {
    if (0.0..1.0).contains(&u) {
        Ok(u)
    } else {
        Err(invalid(format!("{name} must lie in [0, 1), got {u}")))
    }
}

/// Creates a medium from named parameters (see the README's parameter table). Values outside
/// the domain stated there (e.g. `sigma` outside [1e-50, 1e50]) are refused with the reason. On
/// failure nothing is written to `*out_medium` and [`super::mf_last_error_message`] names the
/// parameter. The handle also holds the bounds of the flakes' projected area that the tracking
/// calls take their majorants from, built here once: 88 KiB per medium.
///
/// # Safety
/// `params` must be a live handle (or NULL); `out_medium` NULL or valid for writes.
#[no_mangle]
pub unsafe extern "C" fn mf_medium_new(params: *const mf_params, out_medium: *mut *mut mf_medium) -> mf_status {
    boundary(|| {
        let params = arg(params, "params")?;
        let slot = out(out_medium, "out_medium")?;
        let inner = medium_from_params(&params.inner)?;
        *slot = into_handle(mf_medium { bounds: ProjectedAreaBounds::of(&inner), inner });
        Ok(())
    })
}

/// Releases a medium; NULL is a no-op.
///
/// # Safety
/// `medium` must be NULL or a pointer from [`mf_medium_new`] not yet freed, and no other thread
/// may be using it.
#[no_mangle]
pub unsafe extern "C" fn mf_medium_free(medium: *mut mf_medium) {
    free_handle(medium);
}

/// The signed distance of the shell's top face, `k * sigma` (scene units): the medium's region is
/// every point whose signed distance is below it (the interior included).
///
/// # Safety
/// Pointers must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mf_medium_shell_top(medium: *const mf_medium, out_top: *mut f64) -> mf_status {
    boundary(|| {
        let m = arg(medium, "medium")?;
        let slot = out(out_top, "out_top")?;
        *slot = m.inner.height.top();
        Ok(())
    })
}

/// Extinction `sigma_t(f, d)` (seeds/000 Eq. 14) at signed distance `f` for propagation direction `d`.
///
/// # Safety
/// Pointers must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mf_medium_sigma_t(
    medium: *const mf_medium,
    frame_: *const mf_frame,
    f: f64,
    d: mf_vec3,
    out_sigma_t: *mut f64,
) -> mf_status {
    boundary(|| {
        let m = arg(medium, "medium")?;
        let fr = frame(arg(frame_, "frame")?)?;
        let d = local_direction(&fr, "d", d)?;
        let f = finite("f", f)?;
        let slot = out(out_sigma_t, "out_sigma_t")?;
        *slot = m.inner.sigma_t(f, d);
        Ok(())
    })
}

/// A majorant of `sigma_t` over a segment whose signed distance stays within `[f_a, f_b]` (any
/// order) for direction `d`.
///
/// # Safety
/// Pointers must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mf_medium_majorant(
    medium: *const mf_medium,
    frame_: *const mf_frame,
    f_a: f64,
    f_b: f64,
    d: mf_vec3,
    out_majorant: *mut f64,
) -> mf_status {
    boundary(|| {
        let m = arg(medium, "medium")?;
        let fr = frame(arg(frame_, "frame")?)?;
        let d = local_direction(&fr, "d", d)?;
        let (f_a, f_b) = (finite("f_a", f_a)?, finite("f_b", f_b)?);
        let slot = out(out_majorant, "out_majorant")?;
        *slot = m.inner.majorant(f_a, f_b, d);
        Ok(())
    })
}

/// Validates a segment query; `length_name` is how the caller's API calls the length.
fn flight_args(q: &mf_flight_query, length_name: &str) -> FfiResult<(f64, DVec3, f64)> {
    let fr = frame(&q.frame)?;
    Ok((finite("f", q.f)?, local_direction(&fr, "d", q.d)?, length(length_name, q.t_max)?))
}

/// Optical depth along a segment from signed distance `f` along `d` for length `t` (+inf allowed),
/// with the SDF varying linearly (`f + s * (d . normal)`), in closed form.
///
/// # Safety
/// Pointers must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mf_medium_optical_depth(
    medium: *const mf_medium,
    frame_: *const mf_frame,
    f: f64,
    d: mf_vec3,
    t: f64,
    out_tau: *mut f64,
) -> mf_status {
    boundary(|| {
        let m = arg(medium, "medium")?;
        let q = mf_flight_query { frame: *arg(frame_, "frame")?, f, d, t_max: t, u: 0.0 };
        let (f, d, t) = flight_args(&q, "t")?;
        let slot = out(out_tau, "out_tau")?;
        *slot = m.inner.optical_depth(f, d, t);
        Ok(())
    })
}

/// Transmittance `exp(-tau)` of the same segment as [`mf_medium_optical_depth`].
///
/// # Safety
/// Pointers must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mf_medium_transmittance(
    medium: *const mf_medium,
    frame_: *const mf_frame,
    f: f64,
    d: mf_vec3,
    t: f64,
    out_transmittance: *mut f64,
) -> mf_status {
    boundary(|| {
        let m = arg(medium, "medium")?;
        let q = mf_flight_query { frame: *arg(frame_, "frame")?, f, d, t_max: t, u: 0.0 };
        let (f, d, t) = flight_args(&q, "t")?;
        let slot = out(out_transmittance, "out_transmittance")?;
        *slot = m.inner.transmittance(f, d, t);
        Ok(())
    })
}

fn free_flight(m: &MacrofacetMedium, q: &mf_flight_query) -> FfiResult<mf_free_flight> {
    let (f, d, t_max) = flight_args(q, "t_max")?;
    let u = uniform("u", q.u)?;
    Ok(match m.sample_free_flight(f, d, t_max, u) {
        FreeFlight::Scatter { t } => mf_free_flight { scattered: true, t },
        FreeFlight::Pass => mf_free_flight { scattered: false, t: t_max },
    })
}

/// Samples the distance to the next collision on `[0, t_max]` analytically (density
/// `sigma_t(t) T(t)`); the weight of either outcome is 1 (the albedo lives in the phase function).
///
/// # Safety
/// Pointers must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mf_medium_sample_free_flight(
    medium: *const mf_medium,
    frame_: *const mf_frame,
    f: f64,
    d: mf_vec3,
    t_max: f64,
    u: f64,
    out_flight: *mut mf_free_flight,
) -> mf_status {
    boundary(|| {
        let m = arg(medium, "medium")?;
        let q = mf_flight_query { frame: *arg(frame_, "frame")?, f, d, t_max, u };
        let result = free_flight(&m.inner, &q)?;
        *out(out_flight, "out_flight")? = result;
        Ok(())
    })
}

fn phase_eval(m: &MacrofacetMedium, q: &mf_phase_query) -> FfiResult<(mf_rgb, f64)> {
    let fr = frame(&q.frame)?;
    let wi = local_direction(&fr, "wi", q.wi)?;
    let wo = local_direction(&fr, "wo", q.wo)?;
    let (value, pdf) = m.phase.eval_pdf(wi, wo);
    Ok((rgb(value), pdf))
}

/// The phase function `p(wi, wo)` per channel (seeds/000 Eq. 11, flake reflectance included).
///
/// # Safety
/// Pointers must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mf_phase_eval(
    medium: *const mf_medium,
    frame_: *const mf_frame,
    wi: mf_vec3,
    wo: mf_vec3,
    out_value: *mut mf_rgb,
) -> mf_status {
    boundary(|| {
        let m = arg(medium, "medium")?;
        let fr = frame(arg(frame_, "frame")?)?;
        let (wi, wo) = (local_direction(&fr, "wi", wi)?, local_direction(&fr, "wo", wo)?);
        let slot = out(out_value, "out_value")?;
        *slot = rgb(m.inner.phase.eval(wi, wo));
        Ok(())
    })
}

/// The phase function's value and the density of [`mf_phase_sample`] for one pair of
/// directions in one call (what next-event estimation with MIS needs; for diffuse flakes it
/// runs their quadrature once instead of twice).
///
/// # Safety
/// Pointers must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mf_phase_eval_pdf(
    medium: *const mf_medium,
    frame_: *const mf_frame,
    wi: mf_vec3,
    wo: mf_vec3,
    out_value: *mut mf_phase_value,
) -> mf_status {
    // SAFETY: forwarded under the same contract.
    unsafe { super::mf_phase_eval_pdf_local(medium, std::ptr::null(), frame_, wi, wo, out_value) }
}

/// The density with which [`mf_phase_sample`] picks `wo` (per solid angle).
///
/// # Safety
/// Pointers must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mf_phase_pdf(
    medium: *const mf_medium,
    frame_: *const mf_frame,
    wi: mf_vec3,
    wo: mf_vec3,
    out_pdf: *mut f64,
) -> mf_status {
    boundary(|| {
        let m = arg(medium, "medium")?;
        let fr = frame(arg(frame_, "frame")?)?;
        let (wi, wo) = (local_direction(&fr, "wi", wi)?, local_direction(&fr, "wo", wo)?);
        let slot = out(out_pdf, "out_pdf")?;
        *slot = m.inner.phase.pdf(wi, wo);
        Ok(())
    })
}

fn phase_sample(m: &MacrofacetMedium, q: &mf_phase_sample_query) -> FfiResult<mf_phase_sample_result> {
    phase_sample_with(m, &frame(&q.frame)?, q.wi, q.u)
}

/// One phase sample in a checked frame (also the `_local` calls').
pub(crate) fn phase_sample_with(m: &MacrofacetMedium, fr: &Frame, wi: mf_vec3, u: [f64; MF_PHASE_SAMPLE_DIMENSIONS]) -> FfiResult<mf_phase_sample_result> {
    let wi = local_direction(fr, "wi", wi)?;
    for (i, u) in u.iter().enumerate() {
        uniform(format_args!("u[{i}]"), *u)?;
    }
    // The pdf and weight are those of the world-space `wo` the host gets back, taken to the
    // local frame as `mf_phase_pdf` will take it: then `mf_phase_pdf(frame, wi, sample.wo)` is the
    // sample's pdf bit for bit (issue 9 item 7).
    let sample = m.phase.sample_direction(wi, u).and_then(|wo| {
        let wo_world: mf_vec3 = fr.to_world(wo).into();
        let record = m.phase.sample_record(wi, local_direction(fr, "wo", wo_world).ok()?)?;
        Some((wo_world, record))
    });
    Ok(match sample {
        Some((wo, s)) => mf_phase_sample_result { wo, weight: rgb(s.weight), pdf: s.pdf, valid: true },
        None => mf_phase_sample_result { wo: DVec3::ZERO.into(), weight: rgb([0.0; 3]), pdf: 0.0, valid: false },
    })
}

/// Samples a scattering direction from `wi` (pointing away from the event) with
/// [`MF_PHASE_SAMPLE_DIMENSIONS`] uniform numbers in `[0, 1)` read from `u`. A valid sample's
/// `pdf` is what [`mf_phase_pdf`] returns for the same medium, frame, `wi` and the returned `wo`,
/// bit for bit, and `pdf > 0`; `weight` is [`mf_phase_eval`] divided by it (to rounding).
///
/// # Safety
/// Pointers must be NULL or valid; `u` must hold `MF_PHASE_SAMPLE_DIMENSIONS` doubles.
#[no_mangle]
pub unsafe extern "C" fn mf_phase_sample(
    medium: *const mf_medium,
    frame_: *const mf_frame,
    wi: mf_vec3,
    u: *const f64,
    out_sample: *mut mf_phase_sample_result,
) -> mf_status {
    // SAFETY: forwarded under the same contract.
    unsafe { super::mf_phase_sample_local(medium, std::ptr::null(), frame_, wi, u, out_sample) }
}

/// Runs `one` over a batch; validates every query before anything is written, so that on error
/// the output array is untouched and the message names the failing index.
fn batch<Q, R: Copy>(
    medium: *const mf_medium,
    queries: *const Q,
    count: usize,
    output: *mut R,
    one: impl Fn(&MacrofacetMedium, &Q) -> FfiResult<R>,
) -> mf_status {
    boundary(|| {
        let m = arg(medium, "medium")?;
        if count == 0 {
            return Ok(());
        }
        let first = arg(queries, "queries")?;
        out(output, "out")?;
        // SAFETY: the caller promises `count` readable queries and `count` writable outputs.
        let queries = unsafe { std::slice::from_raw_parts(first, count) };
        let results = queries
            .iter()
            .enumerate()
            .map(|(i, q)| one(&m.inner, q).map_err(|e| FfiError { status: e.status, message: format!("query {i}: {}", e.message) }))
            .collect::<FfiResult<Vec<R>>>()?;
        // SAFETY: see above; `output` is non-NULL.
        unsafe { std::slice::from_raw_parts_mut(output, count) }.copy_from_slice(&results);
        Ok(())
    })
}

/// Batch form of [`mf_medium_transmittance`] (`t_max` is the length, `u` is ignored).
///
/// # Safety
/// `queries` and `out_transmittance` must hold `count` elements (may be NULL when `count` is 0).
#[no_mangle]
pub unsafe extern "C" fn mf_medium_transmittance_batch(
    medium: *const mf_medium,
    queries: *const mf_flight_query,
    count: usize,
    out_transmittance: *mut f64,
) -> mf_status {
    batch(medium, queries, count, out_transmittance, |m, q| {
        let (f, d, t) = flight_args(q, "t_max")?;
        Ok(m.transmittance(f, d, t))
    })
}

/// Batch form of [`mf_medium_sample_free_flight`].
///
/// # Safety
/// `queries` and `out_flights` must hold `count` elements (may be NULL when `count` is 0).
#[no_mangle]
pub unsafe extern "C" fn mf_medium_sample_free_flight_batch(
    medium: *const mf_medium,
    queries: *const mf_flight_query,
    count: usize,
    out_flights: *mut mf_free_flight,
) -> mf_status {
    batch(medium, queries, count, out_flights, free_flight)
}

/// Batch form of [`mf_phase_eval`] and [`mf_phase_pdf`]: the value and the sampling density of
/// each pair.
///
/// # Safety
/// `queries` and `out_values` must hold `count` elements (may be NULL when `count` is 0).
#[no_mangle]
pub unsafe extern "C" fn mf_phase_eval_batch(
    medium: *const mf_medium,
    queries: *const mf_phase_query,
    count: usize,
    out_values: *mut mf_phase_value,
) -> mf_status {
    batch(medium, queries, count, out_values, |m, q| phase_eval(m, q).map(|(value, pdf)| mf_phase_value { value, pdf }))
}

/// Batch form of [`mf_phase_sample`].
///
/// # Safety
/// `queries` and `out_samples` must hold `count` elements (may be NULL when `count` is 0).
#[no_mangle]
pub unsafe extern "C" fn mf_phase_sample_batch(
    medium: *const mf_medium,
    queries: *const mf_phase_sample_query,
    count: usize,
    out_samples: *mut mf_phase_sample_result,
) -> mf_status {
    batch(medium, queries, count, out_samples, phase_sample)
}
