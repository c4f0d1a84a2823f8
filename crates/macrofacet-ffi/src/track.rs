//! `mf_track_*`: the library owns the volume event. A renderer hands it a ray segment inside a
//! macrofacet medium and the mean surface ([`mf_surface`]); it gets back a real collision with its
//! local frame, or a transmittance estimate for a shadow ray. Segments, majorants, frames and
//! the planar closed forms stay inside the library (see `src/tracking.rs`).
//!
//! Random numbers: each call takes a 64-bit `seed` and runs its own PCG32 from it on the stream
//! [`TRACK_STREAM`] (tracking needs an unbounded count of random numbers); the same seed gives
//! the same result. Hosts derive the
//! seed from their sampler (e.g. a hash of pixel, sample index and bounce).

use super::field::{mf_field, mf_local_params, CallbackField};
use super::medium::{mf_frame, mf_medium, mf_vec3};
use super::surface::{with_surface, mf_surface, SurfaceVisitor};
use super::{arg, boundary, mf_status, out, FfiError, FfiResult};
use macrofacet::error::{Error, ErrorKind};
use macrofacet::frame::{not_a_direction, unit_direction};
use macrofacet::medium::MacrofacetMedium;
use macrofacet::rng::Pcg32;
use macrofacet::field::{Constant, MediumField};
use macrofacet::opaque_core::{start_level, OpaqueCore};
use macrofacet::surface::MeanSurface;
use macrofacet::tracking::{ProjectedAreaBounds, TrackStats, TrackedFlight, Tracker, TRACK_STREAM};
use glam::DVec3;
use std::ffi::c_void;

/// One tracking query: the ray `origin + t d` (`d` unit, world space), `t ∈ [0, t_max]`
/// (`t_max` may be `+inf`), inside the medium's region; `seed` drives the call's random numbers.
///
/// `exit_level` 0 (as zero-initialised): the host has cast the ray to its region boundary's
/// exit and passes that as `t_max`. Otherwise the boundary's exit level
/// ([`mf_enclosure_exit_level`], or for a host's own boundary a level of `f` that no point it
/// encloses exceeds; at least `mf_medium_shell_top`): the call then also ends where it finds the
/// ray outside the boundary, and a ray that passed reports where (`mf_collision::t`,
/// `mf_transmittance::t`), so the host continues it from there, outside, without a ray cast
/// for the exit. Only valid where no other geometry lies within `exit_level` of the surface's
/// bounding box (`mf_surface_bounding_box`): the call tracks the medium wherever the ray goes
/// until it finds it outside. Same results as the ray cast: the shell's density is zero between
/// its top and the boundary.
///
/// `survival` 0 (as zero-initialised) or 1: the host kept the ray unconditionally. Otherwise, for
/// [`mf_track_transmittance`] only, the probability in `(0, 1)` with which it kept this shadow
/// ray in a Russian roulette of its own ([`mf_track_depth_roulette`]): the estimate is then of
/// `T / survival` (the host multiplies by nothing more), and the call's own roulette counts
/// that weight.
///
/// `hint` 0 (as zero-initialised): none. Otherwise, for a call that starts where a collision
/// was (its escape flight, its shadow rays), that collision's [`mf_collision::hint`]: the call's
/// first surface query begins its search there (on a mesh, at the collision's triangle). Any
/// value is safe: a stale or foreign hint costs at most the search it fails to save, and the
/// results are the same up to the rounding of another way to the same closest point.
///
/// [`mf_enclosure_exit_level`]: crate::surface::mf_enclosure_exit_level
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct mf_track_query {
    pub origin: mf_vec3,
    pub d: mf_vec3,
    pub t_max: f64,
    pub seed: u64,
    pub exit_level: f64,
    pub survival: f64,
    pub hint: u64,
}

/// What one tracking call cost: surface queries (callbacks), tracked segments (bound queries),
/// tentative collisions, and majorant violations — tentative collisions where the true
/// extinction exceeded the majorant because the surface's bounds were wrong (0 for a correct
/// surface; a non-zero count means a biased result).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct mf_track_stats {
    pub surface_queries: u32,
    pub segments: u32,
    pub tentative_collisions: u32,
    pub majorant_violations: u32,
}

/// The outcome of [`mf_track_free_flight`]. When `scattered`, a real collision happened at
/// `t` (`0 <= t <= t_max`), at `p` where the signed distance is `f` and the local frame of the
/// phase function is `frame`; otherwise the ray passed the segment (the other fields are zero and
/// `t = t_max`, or with an exit level where the ray left the region). The weight of either outcome is 1: the flakes' albedo is in the phase function.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct mf_collision {
    pub scattered: bool,
    pub t: f64,
    pub p: mf_vec3,
    pub f: f64,
    pub frame: mf_frame,
    /// The field's parameters at the collision (`set = 0` without a field or when passing).
    pub local: mf_local_params,
    pub stats: mf_track_stats,
    /// Where the surface found the collision, for the calls that start there
    /// ([`mf_track_query::hint`]); 0 for none (and when passing).
    pub hint: u64,
}

/// The outcome of [`mf_track_transmittance`]: an unbiased estimate in `[0, 1]` over `[0, t]`:
/// `t = t_max`, or with an exit level where the ray left the region (where the estimate
/// reached 0, where it did).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct mf_transmittance {
    pub transmittance: f64,
    pub t: f64,
    pub stats: mf_track_stats,
}

impl From<TrackStats> for mf_track_stats {
    fn from(s: TrackStats) -> Self {
        mf_track_stats { surface_queries: s.surface_queries, segments: s.segments, tentative_collisions: s.tentative_collisions, majorant_violations: s.majorant_violations }
    }
}

/// A validated query, as the tracker takes it.
#[derive(Clone, Copy)]
struct Ray {
    origin: DVec3,
    d: DVec3,
    t_max: f64,
    /// `+inf` for none (the tracker checks it against the shell's top).
    exit_level: f64,
    /// 1 for none.
    survival: f64,
    hint: u64,
}

/// A query's validated `survival` (0 as 1); only transmittances take one below 1.
fn survival(q: &mf_track_query, transmittance: bool) -> FfiResult<f64> {
    match q.survival {
        0.0 | 1.0 => Ok(1.0),
        p if transmittance && p > 0.0 && p < 1.0 => Ok(p),
        p if transmittance => Err(Error::new(ErrorKind::InvalidArgument, format!("survival must be 0 (none) or in (0, 1], got {p}")).into()),
        p => Err(Error::new(ErrorKind::InvalidArgument, format!("survival applies to transmittances only: a free flight's must be 0 or 1, got {p}")).into()),
    }
}

/// A validated query, for a transmittance or a free flight.
fn query(q: &mf_track_query, transmittance: bool) -> FfiResult<Ray> {
    let origin = DVec3::from(q.origin);
    if !origin.is_finite() {
        return Err(Error::new(ErrorKind::InvalidArgument, format!("origin must be finite, got {origin}")).into());
    }
    let Some(d) = unit_direction(q.d.into()) else { return Err(not_a_direction("d", q.d.into()).into()) };
    if !(q.t_max >= 0.0) {
        return Err(Error::new(ErrorKind::InvalidArgument, format!("t_max must be >= 0 (or +inf), got {}", q.t_max)).into());
    }
    let exit_level = match q.exit_level {
        0.0 => f64::INFINITY,
        level if level.is_finite() && level > 0.0 => level,
        level => return Err(Error::new(ErrorKind::InvalidArgument, format!("exit_level must be 0 (none) or finite and at least the shell's top, got {level}")).into()),
    };
    Ok(Ray { origin, d, t_max: q.t_max, exit_level, survival: survival(q, transmittance)?, hint: q.hint })
}

/// One call: a free flight or a transmittance, with the field (if any) and the host's data. The
/// result is written into `out` once the call has succeeded (nothing is written on an error):
/// in place, because `mf_collision` is 232 bytes and moving it out through the visitor, the
/// `Result`s and the C boundary took a third of the calls' `memcpy` traffic.
struct Call<'a> {
    out: Out<'a>,
    medium: &'a MacrofacetMedium,
    bounds: &'a ProjectedAreaBounds,
    field: Option<&'a mf_field>,
    user_data: *mut c_void,
    ray: Ray,
    seed: u64,
}

/// What a call computes, and where it goes.
enum Out<'a> {
    FreeFlight(&'a mut mf_collision),
    Transmittance(&'a mut mf_transmittance),
}

impl SurfaceVisitor for Call<'_> {
    type Output = macrofacet::error::Result<()>;
    fn visit<S: MeanSurface>(self, surface: &S) -> Self::Output {
        match self.field {
            // The collision reports no uv: the tracker need not complete it.
            None => {
                let tracker = Tracker::with_bounds(self.medium, self.bounds, surface, &Constant).without_uv().from_hint(self.ray.hint).after_roulette(self.ray.survival)?;
                run(self.out, self.ray, self.seed, &tracker)
            }
            Some(field) => {
                let field = CallbackField::new(field, self.user_data);
                let tracker = Tracker::with_bounds(self.medium, self.bounds, surface, &field).without_uv().from_hint(self.ray.hint).after_roulette(self.ray.survival)?;
                run(self.out, self.ray, self.seed, &tracker)
            }
        }
    }
}

/// The collision record of a ray that passed to `t` (the other fields zero).
fn passed(t: f64, stats: mf_track_stats) -> mf_collision {
    let zero = DVec3::ZERO.into();
    mf_collision { scattered: false, t, p: zero, f: 0.0, frame: mf_frame { normal: zero, tangent: zero }, local: mf_local_params::NONE, stats, hint: 0 }
}

fn run<S: MeanSurface, F: MediumField>(out: Out<'_>, ray: Ray, seed: u64, tracker: &Tracker<S, F>) -> macrofacet::error::Result<()> {
    let mut stats = TrackStats::default();
    let Ray { origin, d, t_max, exit_level, .. } = ray;
    let rng = &mut Pcg32::new(seed, TRACK_STREAM);
    let exits = exit_level.is_finite();
    match out {
        Out::FreeFlight(slot) => {
            let (flight, t_end) = if exits { tracker.sample_free_flight_to_exit(origin, d, t_max, exit_level, rng, &mut stats)? } else { (tracker.sample_free_flight(origin, d, t_max, rng, &mut stats)?, t_max) };
            *slot = match flight {
                TrackedFlight::Scatter { t, point, local, hint } => mf_collision {
                    scattered: true,
                    t,
                    p: (origin + t * d).into(),
                    f: point.f,
                    frame: mf_frame { normal: point.normal.into(), tangent: point.tangent.into() },
                    local: (&local).into(),
                    stats: stats.into(),
                    hint,
                },
                TrackedFlight::Pass => passed(t_end, stats.into()),
            };
        }
        Out::Transmittance(slot) => {
            let (transmittance, t) = if exits { tracker.transmittance_to_exit(origin, d, t_max, exit_level, rng, &mut stats)? } else { (tracker.transmittance(origin, d, t_max, rng, &mut stats)?, t_max) };
            *slot = mf_transmittance { transmittance, t, stats: stats.into() };
        }
    }
    Ok(())
}

/// The optional field argument.
pub(super) fn field_arg<'a>(field: *const mf_field) -> Option<&'a mf_field> {
    // SAFETY: NULL or a live handle, as the caller promises.
    unsafe { field.as_ref() }
}

fn track(out: Out<'_>, medium: &mf_medium, surface: &mf_surface, field: Option<&mf_field>, user_data: *mut c_void, q: &mf_track_query) -> FfiResult<()> {
    let ray = query(q, matches!(out, Out::Transmittance(_)))?;
    let call = Call { out, medium: &medium.inner, bounds: &medium.bounds, field, user_data, ray, seed: q.seed };
    Ok(with_surface(surface, user_data, call)?)
}

fn free_flight(medium: &mf_medium, surface: &mf_surface, field: Option<&mf_field>, user_data: *mut c_void, q: &mf_track_query, out: &mut mf_collision) -> FfiResult<()> {
    track(Out::FreeFlight(out), medium, surface, field, user_data, q)
}

fn transmittance(medium: &mf_medium, surface: &mf_surface, field: Option<&mf_field>, user_data: *mut c_void, q: &mf_track_query, out: &mut mf_transmittance) -> FfiResult<()> {
    track(Out::Transmittance(out), medium, surface, field, user_data, q)
}

/// Samples a free flight along `query`'s ray through the medium around `surface`: the distance
/// to the next real collision, with its local frame (for `mf_phase_*`). Delta tracking against
/// majorants built from the planar closed forms and the surface's segment bounds: exact (every
/// tentative collision real) for a planar surface, unbiased for any surface whose bounds hold.
/// `field` (NULL for a stationary medium) gives spatially varying parameters; the collision then
/// reports them in `local`, for `mf_phase_sample_local` / `mf_phase_eval_pdf_local`.
/// `user_data` is passed to the surface's and the field's callbacks. Errors: invalid arguments, a
/// callback's failure or invalid answer (NaN, non-unit normal, inconsistent bound) — reported at
/// once.
///
/// # Safety
/// Pointers must be NULL or valid; the callbacks must be safe to call with `user_data`.
#[no_mangle]
pub unsafe extern "C" fn mf_track_free_flight(
    medium: *const mf_medium,
    surface: *const mf_surface,
    field: *const mf_field,
    user_data: *mut c_void,
    query: *const mf_track_query,
    out_collision: *mut mf_collision,
) -> mf_status {
    boundary(|| {
        let (m, s, q) = (arg(medium, "medium")?, arg(surface, "surface")?, arg(query, "query")?);
        free_flight(m, s, field_arg(field), user_data, q, out(out_collision, "out_collision")?)
    })
}

/// An unbiased estimate of the transmittance along `query`'s ray (shadow rays): residual ratio
/// tracking with an analytic control, so a thin shell's shadow ray rarely needs a surface query.
///
/// # Safety
/// As [`mf_track_free_flight`].
#[no_mangle]
pub unsafe extern "C" fn mf_track_transmittance(
    medium: *const mf_medium,
    surface: *const mf_surface,
    field: *const mf_field,
    user_data: *mut c_void,
    query: *const mf_track_query,
    out_transmittance: *mut mf_transmittance,
) -> mf_status {
    boundary(|| {
        let (m, s, q) = (arg(medium, "medium")?, arg(surface, "surface")?, arg(query, "query")?);
        transmittance(m, s, field_arg(field), user_data, q, out(out_transmittance, "out_transmittance")?)
    })
}

/// Runs `one` over a batch: validates every query first, then tracks them; on any error nothing
/// is written and the message names the failing index. (The two batch calls' C arguments, and
/// what differs between them.)
#[allow(clippy::too_many_arguments)]
fn track_batch<R: Copy>(
    medium: *const mf_medium,
    surface: *const mf_surface,
    field: *const mf_field,
    user_data: *mut c_void,
    queries: *const mf_track_query,
    count: usize,
    output: *mut R,
    blank: R,
    transmittances: bool,
    one: impl Fn(&mf_medium, &mf_surface, Option<&mf_field>, *mut c_void, &mf_track_query, &mut R) -> FfiResult<()>,
) -> mf_status {
    boundary(|| {
        let (m, s) = (arg(medium, "medium")?, arg(surface, "surface")?);
        if count == 0 {
            return Ok(());
        }
        let first = arg(queries, "queries")?;
        out(output, "out")?;
        // SAFETY: the caller promises `count` readable queries and `count` writable outputs.
        let queries = unsafe { std::slice::from_raw_parts(first, count) };
        let at = |i: usize, e: FfiError| FfiError { status: e.status, message: format!("query {i}: {}", e.message) };
        for (i, q) in queries.iter().enumerate() {
            query(q, transmittances).map_err(|e| at(i, e))?;
        }
        // Results go to an array of blanks first, so that an error leaves the host's unchanged.
        let mut results = vec![blank; count];
        for (i, (q, r)) in queries.iter().zip(results.iter_mut()).enumerate() {
            one(m, s, field_arg(field), user_data, q, r).map_err(|e| at(i, e))?;
        }
        // SAFETY: see above; `output` is non-NULL.
        unsafe { std::slice::from_raw_parts_mut(output, count) }.copy_from_slice(&results);
        Ok(())
    })
}

/// Batch form of [`mf_track_free_flight`] for wavefront renderers (one `user_data` for all).
///
/// # Safety
/// `queries` and `out_collisions` must hold `count` elements (may be NULL when `count` is 0).
#[no_mangle]
pub unsafe extern "C" fn mf_track_free_flight_batch(
    medium: *const mf_medium,
    surface: *const mf_surface,
    field: *const mf_field,
    user_data: *mut c_void,
    queries: *const mf_track_query,
    count: usize,
    out_collisions: *mut mf_collision,
) -> mf_status {
    track_batch(medium, surface, field, user_data, queries, count, out_collisions, passed(0.0, TrackStats::default().into()), false, free_flight)
}

/// Batch form of [`mf_track_transmittance`].
///
/// # Safety
/// `queries` and `out_transmittances` must hold `count` elements (may be NULL when `count` is 0).
#[no_mangle]
pub unsafe extern "C" fn mf_track_transmittance_batch(
    medium: *const mf_medium,
    surface: *const mf_surface,
    field: *const mf_field,
    user_data: *mut c_void,
    queries: *const mf_track_query,
    count: usize,
    out_transmittances: *mut mf_transmittance,
) -> mf_status {
    let blank = mf_transmittance { transmittance: 0.0, t: 0.0, stats: TrackStats::default().into() };
    track_batch(medium, surface, field, user_data, queries, count, out_transmittances, blank, true, transmittance)
}

/// A Russian roulette on a shadow ray before the host evaluates or tracks anything for it: the
/// ray descends from height `f_from` (at most the start's `f`) to `f_to` (at least the deepest
/// `f` it reaches; for a sphere, its chord's closest approach), and its transmittance in
/// `medium` about `surface` is at most `exp(−κ [ln Φ(min(f_from, top)/σ) − ln Φ(f_to/σ)])` (the
/// bound of `mf_track_opaque_core`). With `u` uniform in `[0, 1)` (the host's), writes the
/// probability with which the ray is kept, `min(1, bound / 0.5)`, or 0 when it is not: its
/// estimate is then 0, with no phase value and no tracking. A kept ray's
/// `mf_track_transmittance` takes it as `mf_track_query::survival` and estimates `T / survival`,
/// its own roulette (at 0.5) counting the weight, so that the estimates are those the call
/// would have made alone, a shallow ray's costs saved. `f_to >= f_from` (a ray that does not
/// descend) keeps the ray with probability 1. For stationary parameters only (as
/// `mf_track_opaque_core`; with a varying field the bound does not hold: estimates stay
/// unbiased, but may be larger). No callback is called. Errors: NaN levels, `u` outside
/// `[0, 1)`, NULL pointers (nothing written).
///
/// # Safety
/// Pointers must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mf_track_depth_roulette(medium: *const mf_medium, surface: *const mf_surface, f_from: f64, f_to: f64, u: f64, out_survival: *mut f64) -> mf_status {
    struct Roulette<'a> {
        medium: &'a mf_medium,
        levels: (f64, f64),
        u: f64,
    }
    impl SurfaceVisitor for Roulette<'_> {
        type Output = f64;
        fn visit<S: MeanSurface>(self, surface: &S) -> f64 {
            let tracker = Tracker::with_bounds(&self.medium.inner, &self.medium.bounds, surface, &Constant);
            tracker.depth_roulette(self.levels.0, self.levels.1, self.u).unwrap_or(1.0)
        }
    }
    boundary(|| {
        let (m, s) = (arg(medium, "medium")?, arg(surface, "surface")?);
        let survival = out(out_survival, "out_survival")?;
        if f_from.is_nan() || f_to.is_nan() {
            return Err(Error::new(ErrorKind::InvalidArgument, format!("levels must not be NaN, got f_from {f_from}, f_to {f_to}")).into());
        }
        if !(0.0..1.0).contains(&u) {
            return Err(Error::new(ErrorKind::InvalidArgument, format!("u must be in [0, 1), got {u}")).into());
        }
        *survival = with_surface(s, std::ptr::null_mut(), Roulette { medium: m, levels: (f_from, f_to), u });
        Ok(())
    })
}

/// The opaque core of `medium` about `surface` (stationary parameters; see the Rust crate's
/// `opaque_core` module for the bound): a ray from a point with `f >= *out_start_level` that
/// reaches `f <= *out_core_level` has a transmittance below `e^-750`, so small that its estimate
/// rounds to 0 in double precision. A host may treat the region `f <= core_level` as opaque for
/// such rays, e.g. skip a shadow ray from a collision (its `f` at least `start_level`) that meets
/// a sphere's core, before the phase evaluation and the tracking call. `*out_start_level` is
/// `−8σ`; `*out_core_level` is `−INFINITY` when the bound gives no core (a projected area
/// without a positive lower bound over the directions a descending ray takes: on a mesh, whose
/// frame normals are not the distance's gradient, over every direction). A medium with a field
/// (`mf_track_*`'s `field`) varies in space: the levels do not hold for it.
///
/// # Safety
/// Pointers must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mf_track_opaque_core(medium: *const mf_medium, surface: *const mf_surface, out_start_level: *mut f64, out_core_level: *mut f64) -> mf_status {
    struct Core<'a>(&'a mf_medium);
    impl SurfaceVisitor for Core<'_> {
        type Output = Option<OpaqueCore>;
        fn visit<S: MeanSurface>(self, surface: &S) -> Option<OpaqueCore> {
            Tracker::with_bounds(&self.0.inner, &self.0.bounds, surface, &Constant).opaque_core()
        }
    }
    boundary(|| {
        let (m, s) = (arg(medium, "medium")?, arg(surface, "surface")?);
        let (start, core) = (out(out_start_level, "out_start_level")?, out(out_core_level, "out_core_level")?);
        // (No callback is called: only the surface's Lipschitz constant and kind are read.)
        let found = with_surface(s, std::ptr::null_mut(), Core(m));
        (*start, *core) = match found {
            Some(c) => (c.start_level, c.core_level),
            None => (start_level(&m.inner.height), f64::NEG_INFINITY),
        };
        Ok(())
    })
}
