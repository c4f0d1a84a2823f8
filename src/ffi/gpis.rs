//! `mf_gpis`: the realization-based GPIS ground truth (seeds/004) for a host's path tracer, so
//! that one scene renders with the statistical `mf_medium` and with realizations side by side.
//!
//! A GPIS is a stochastic *surface*: each call to [`mf_gpis_trace`] realizes the Gaussian process
//! along one ray segment (conditioned per the memory model on the previous crossing) and returns
//! its first entering zero crossing with a sampled normal; the host then reflects about that
//! normal with [`mf_gpis_scatter`]. The mean of the process is the host's signed distance,
//! supplied by a callback. Kernel axes are world axes (use an isotropic kernel on curved
//! shapes). The random numbers of a trace come from a generator the call seeds with the host's
//! 64-bit `seed` (a trace needs an unbounded count of them); same seed, same realization.

use super::medium::{mf_phase_sample_result, mf_rgb, mf_vec3};
use super::{arg, boundary, free_handle, into_handle, mf_params, mf_status, out, FfiError};
use crate::error::{Error, ErrorKind};
use crate::frame::check_direction;
use crate::gpis::{GpisSurface, MeanSdf, StartState, Trace};
use crate::params::gpis_from_params;
use crate::stats::Pcg32;
use glam::DVec3;
use std::ffi::c_void;

/// [`mf_gpis_start::kind`]: the segment starts in free space (camera or light ray): the origin
/// value is drawn from the prior conditioned on `f > 0`.
pub const MF_GPIS_START_FREE: u32 = 0;
/// [`mf_gpis_start::kind`]: the segment starts at the previous crossing (`f = 0`), and, with
/// `memory = renewal_plus`, remembers its gradient.
pub const MF_GPIS_START_ON_SURFACE: u32 = 1;

/// The mean signed distance and its gradient at a point, as the host's callback returns them.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct mf_sdf_sample {
    pub f: f64,
    pub gradient: mf_vec3,
}

/// The host's mean signed distance: writes `f(p)` and `∇f(p)` (world space) to `out`. Must not
/// unwind; a NaN or infinite answer makes the trace fail with `MF_ERROR_INVALID_ARGUMENT`.
pub type mf_sdf_fn = Option<unsafe extern "C" fn(user_data: *mut c_void, p: mf_vec3, out: *mut mf_sdf_sample)>;

/// Where a traced segment starts: `kind` is `MF_GPIS_START_FREE` or `MF_GPIS_START_ON_SURFACE`;
/// `gradient` is the previous crossing's sampled gradient (used with `renewal_plus` only).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct mf_gpis_start {
    pub kind: u32,
    pub gradient: mf_vec3,
}

/// The first entering crossing of a realization: `hit` false when the ray leaves the band of the
/// mean surface or reaches `t_max` first (the other fields are then zero). `normal` is outward
/// (`normal . d < 0`); `gradient` is the sampled, unnormalised gradient to pass on to the next
/// segment's [`mf_gpis_start`].
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct mf_gpis_hit {
    pub hit: bool,
    pub t: f64,
    pub point: mf_vec3,
    pub normal: mf_vec3,
    pub gradient: mf_vec3,
}

/// An immutable GPIS configuration; safe to share between threads.
pub struct mf_gpis {
    inner: GpisSurface,
}

/// Adapts the host callback to [`MeanSdf`]. A non-finite answer is passed on as NaN: the march
/// stops at the first one ([`Trace::InvalidMean`]).
struct CallbackMean {
    sdf: unsafe extern "C" fn(*mut c_void, mf_vec3, *mut mf_sdf_sample),
    user_data: *mut c_void,
}

impl CallbackMean {
    fn eval(&self, p: DVec3) -> (f64, DVec3) {
        let mut s = mf_sdf_sample { f: f64::NAN, gradient: mf_vec3 { x: f64::NAN, y: f64::NAN, z: f64::NAN } };
        // SAFETY: the host promised a callable function; it writes one mf_sdf_sample.
        unsafe { (self.sdf)(self.user_data, p.into(), &mut s) };
        let g = DVec3::from(s.gradient);
        if s.f.is_finite() && g.is_finite() {
            (s.f, g)
        } else {
            (f64::NAN, DVec3::NAN)
        }
    }
}

impl MeanSdf for CallbackMean {
    fn value(&self, p: DVec3) -> f64 {
        self.eval(p).0
    }
    fn gradient(&self, p: DVec3) -> DVec3 {
        self.eval(p).1
    }
}

fn invalid(message: String) -> FfiError {
    Error::new(ErrorKind::InvalidArgument, message).into()
}

/// Creates a GPIS from named parameters: the macrofacet medium's names (`sigma`, `variance`,
/// `shell_extent` = half-width of the sampled band in σ, default 6, `distribution` gpss |
/// beckmann, `alpha*`, `lengthscale*`, `material`, `eta`, `k`, `specular_reflectance`) plus
/// `memory` (renewal | renewal_plus, default renewal_plus) and `step_correlation` (default 0.95).
/// The medium's domain applies, and the march is bounded: parameters whose march across the band
/// at normal incidence would take more than 1e4 samples (`alpha` above about 377 at the defaults)
/// are refused, naming what to change.
///
/// # Safety
/// `params` must be a live handle (or NULL); `out_gpis` NULL or valid for writes.
#[no_mangle]
pub unsafe extern "C" fn mf_gpis_new(params: *const mf_params, out_gpis: *mut *mut mf_gpis) -> mf_status {
    boundary(|| {
        let params = arg(params, "params")?;
        let slot = out(out_gpis, "out_gpis")?;
        let inner = gpis_from_params(&params.inner)?;
        *slot = into_handle(mf_gpis { inner });
        Ok(())
    })
}

/// Releases a GPIS; NULL is a no-op.
///
/// # Safety
/// `gpis` must be NULL or a pointer from [`mf_gpis_new`] not yet freed, unused by other threads.
#[no_mangle]
pub unsafe extern "C" fn mf_gpis_free(gpis: *mut mf_gpis) {
    free_handle(gpis);
}

/// The half-width of the band around the mean surface where realizations are sampled
/// (`shell_extent * sigma`, scene units): rays may start at `f = envelope` with
/// `MF_GPIS_START_FREE`.
///
/// # Safety
/// Pointers must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mf_gpis_envelope(gpis: *const mf_gpis, out_envelope: *mut f64) -> mf_status {
    boundary(|| {
        let g = arg(gpis, "gpis")?;
        *out(out_envelope, "out_envelope")? = g.inner.envelope();
        Ok(())
    })
}

/// Realizes the GPIS along `origin + t d`, `0 < t <= t_max` (+inf allowed), and returns its first
/// entering crossing. `sdf(user_data, p, out)` supplies the mean; `seed` the random stream.
///
/// An on-surface start whose realization enters at once (Renewal forgets the slope at the start;
/// with Renewal+ a direction into the remembered surface, e.g. a shadow ray) reports its crossing
/// at a small `t > 0` (at most 2^-16 of a march step). A NaN or infinite answer of `sdf` ends the
/// call with `MF_ERROR_INVALID_ARGUMENT` at most 5 calls after it; with `memory = renewal_plus`,
/// `start.gradient` must lie within 40 standard deviations of the prior slope at `origin` (any
/// gradient a previous `mf_gpis_hit` returned does) and is checked before the march.
///
/// # Safety
/// Pointers must be NULL or valid; `sdf` must be safe to call with `user_data` from this thread.
#[no_mangle]
pub unsafe extern "C" fn mf_gpis_trace(
    gpis: *const mf_gpis,
    sdf: mf_sdf_fn,
    user_data: *mut c_void,
    origin: mf_vec3,
    d: mf_vec3,
    t_max: f64,
    start: *const mf_gpis_start,
    seed: u64,
    out_hit: *mut mf_gpis_hit,
) -> mf_status {
    boundary(|| {
        let g = arg(gpis, "gpis")?;
        let sdf = sdf.ok_or_else(|| FfiError::null("sdf"))?;
        let start = arg(start, "start")?;
        let origin = DVec3::from(origin);
        if !origin.is_finite() {
            return Err(invalid(format!("origin must be finite, got {origin}")));
        }
        let d = check_direction("d", d.into())?;
        if !(t_max > 0.0) {
            return Err(invalid(format!("t_max must be > 0 (or +inf), got {t_max}")));
        }
        let slot = out(out_hit, "out_hit")?;
        let mean = CallbackMean { sdf, user_data };
        let state = match start.kind {
            MF_GPIS_START_FREE => StartState::Uncorrelated,
            MF_GPIS_START_ON_SURFACE => {
                let grad = DVec3::from(start.gradient);
                if !grad.is_finite() {
                    return Err(invalid(format!("start.gradient must be finite, got {grad}")));
                }
                if g.inner.memory == crate::gpis::Memory::RenewalPlus {
                    g.inner.check_start_gradient(&mean, origin, grad)?;
                }
                StartState::OnSurface { gradient: (g.inner.memory == crate::gpis::Memory::RenewalPlus).then_some(grad) }
            }
            other => return Err(invalid(format!("start.kind must be MF_GPIS_START_FREE or MF_GPIS_START_ON_SURFACE, got {other}"))),
        };
        let mut rng = Pcg32::new(seed, 0x6d66_6770_6973); // "mfgpis"
        let trace = g.inner.trace(&mean, origin, d, t_max, &state, &mut || rng.next_f64());
        let zero = mf_vec3 { x: 0.0, y: 0.0, z: 0.0 };
        *slot = match trace {
            Trace::Hit(c) => mf_gpis_hit { hit: true, t: c.t, point: c.point.into(), normal: c.normal.into(), gradient: c.gradient.into() },
            Trace::Miss | Trace::Exhausted { .. } => mf_gpis_hit { hit: false, t: 0.0, point: zero, normal: zero, gradient: zero },
            Trace::InvalidMean { point } => {
                return Err(invalid(format!("the sdf callback returned a NaN or infinite value or gradient at {point}")))
            }
        };
        Ok(())
    })
}

/// Specular reflection at a crossing: `wi` (pointing away, `wi = -d`) about the unit `normal`.
/// The result's `pdf` is 0: the reflection is a delta, so it takes no part in MIS. `valid` is
/// false when `wi` lies behind the normal.
///
/// # Safety
/// Pointers must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mf_gpis_scatter(
    gpis: *const mf_gpis,
    wi: mf_vec3,
    normal: mf_vec3,
    out_sample: *mut mf_phase_sample_result,
) -> mf_status {
    boundary(|| {
        let g = arg(gpis, "gpis")?;
        let wi = check_direction("wi", wi.into())?;
        let n = check_direction("normal", normal.into())?;
        let slot = out(out_sample, "out_sample")?;
        let zero = mf_vec3 { x: 0.0, y: 0.0, z: 0.0 };
        *slot = match g.inner.reflect(wi, n) {
            Some((wo, w)) => mf_phase_sample_result { wo: wo.into(), weight: mf_rgb { r: w[0], g: w[1], b: w[2] }, pdf: 0.0, valid: true },
            None => mf_phase_sample_result { wo: zero, weight: mf_rgb { r: 0.0, g: 0.0, b: 0.0 }, pdf: 0.0, valid: false },
        };
        Ok(())
    })
}
