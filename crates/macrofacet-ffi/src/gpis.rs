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
//!
//! Spatially varying parameters come from an `mf_field` (NULL: stationary), the same fields the
//! tracking calls take: the kernel becomes the non-stationary kernel of seeds/004 Eqs. 25–26
//! whose local `σ(x)` and `Σ(x)` the field gives (roughness form `l_i = √2 σ(x)/α_i(x)` along
//! the world axes, or the anisotropy `Σ(x)` as is; see `src/gpis/nonstationary.rs`). A crossing
//! reports the field's parameters there for [`mf_gpis_scatter`].

use super::field::{mf_field, mf_local_params, CallbackField};
use super::medium::{mf_phase_sample_result, mf_rgb, mf_vec3};
use super::track::field_arg;
use super::{arg, boundary, free_handle, into_handle, mf_params, mf_status, out, FfiError};
use macrofacet::error::{Error, ErrorKind};
use macrofacet::field::{Constant, LocalParams, MediumField};
use macrofacet::frame::check_direction;
use macrofacet_gpis::{GpisSurface, MeanSdf, StartState, Trace};
use macrofacet_gpis::gpis_from_params;
use macrofacet::rng::Pcg32;
use glam::{DVec2, DVec3};
use std::cell::Cell;
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
    /// Texture coordinates of the mean surface's closest point (for fields painted over it; the
    /// library sets 0 before the call, a host may leave them).
    pub u: f64,
    pub v: f64,
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
/// segment's [`mf_gpis_start`]; `local` the field's parameters at the crossing (`set = 0`
/// without a field), for [`mf_gpis_scatter`].
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct mf_gpis_hit {
    pub hit: bool,
    pub t: f64,
    pub point: mf_vec3,
    pub normal: mf_vec3,
    pub gradient: mf_vec3,
    pub local: mf_local_params,
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
    /// Set at the first non-finite answer.
    failed: Cell<bool>,
}

impl CallbackMean {
    fn eval(&self, p: DVec3) -> (f64, DVec3, DVec2) {
        let nan = f64::NAN;
        let mut s = mf_sdf_sample { f: nan, gradient: mf_vec3 { x: nan, y: nan, z: nan }, u: 0.0, v: 0.0 };
        // SAFETY: the host promised a callable function; it writes one mf_sdf_sample.
        unsafe { (self.sdf)(self.user_data, p.into(), &mut s) };
        let (g, uv) = (DVec3::from(s.gradient), DVec2::new(s.u, s.v));
        if s.f.is_finite() && g.is_finite() && uv.is_finite() {
            (s.f, g, uv)
        } else {
            // The field (textures) may look up the uv before the march sees the NaN.
            self.failed.set(true);
            (f64::NAN, DVec3::NAN, DVec2::ZERO)
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
    fn uv(&self, p: DVec3) -> DVec2 {
        self.eval(p).2
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
/// (`shell_extent * sigma`, scene units; with a `field`, `shell_extent * sigma_max` of the
/// field, NULL: stationary): rays may start at `f = envelope` with `MF_GPIS_START_FREE`.
///
/// # Safety
/// Pointers must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mf_gpis_envelope(gpis: *const mf_gpis, field: *const mf_field, out_envelope: *mut f64) -> mf_status {
    boundary(|| {
        let g = arg(gpis, "gpis")?;
        let envelope = match field_arg(field) {
            None => g.inner.envelope(&Constant),
            Some(f) => g.inner.envelope(&CallbackField::new(f, std::ptr::null_mut())),
        };
        *out(out_envelope, "out_envelope")? = envelope;
        Ok(())
    })
}

/// Realizes the GPIS along `origin + t d`, `0 < t <= t_max` (+inf allowed), and returns its first
/// entering crossing. `sdf(user_data, p, out)` supplies the mean; `field` (NULL for a stationary
/// GPIS) the kernel's local parameters, its callbacks called with the same `user_data`; `seed`
/// the random stream. Errors: invalid arguments, a NaN/infinite mean, a field callback's
/// failure (`MF_ERROR_CALLBACK`) or invalid parameters (a `sigma` above the field's
/// `sigma_max`, a non-positive-definite anisotropy, ...) — nothing is written then.
///
/// An on-surface start whose realization enters at once (Renewal forgets the slope at the start;
/// with Renewal+ a direction into the remembered surface, e.g. a shadow ray) reports its crossing
/// at a small `t > 0` (at most 2^-16 of a march step). A NaN or infinite answer of `sdf` ends the
/// call with `MF_ERROR_INVALID_ARGUMENT` at most 5 calls after it; with `memory = renewal_plus`,
/// `start.gradient` must lie within 40 standard deviations of the prior slope at `origin` (any
/// gradient a previous `mf_gpis_hit` returned does) and is checked before the march.
///
/// # Safety
/// Pointers must be NULL or valid; `sdf` and the field's callbacks must be safe to call with
/// `user_data` from this thread.
#[no_mangle]
pub unsafe extern "C" fn mf_gpis_trace(
    gpis: *const mf_gpis,
    sdf: mf_sdf_fn,
    field: *const mf_field,
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
        let mean = CallbackMean { sdf, user_data, failed: Cell::new(false) };
        let trace = match field_arg(field) {
            None => trace_with_field(&g.inner, &mean, &Constant, origin, d, t_max, start, seed),
            Some(f) => trace_with_field(&g.inner, &mean, &CallbackField::new(f, user_data), origin, d, t_max, start, seed),
        };
        let zero = mf_vec3 { x: 0.0, y: 0.0, z: 0.0 };
        *slot = match trace {
            Ok(Trace::InvalidMean { point }) => {
                return Err(invalid(format!("the sdf callback returned a NaN or infinite value or gradient at {point}")))
            }
            // A failed mean may also have misled the field: it is the first cause.
            _ if mean.failed.get() => return Err(invalid("the sdf callback returned a NaN or infinite value or gradient".into())),
            Ok(Trace::Hit(c)) => mf_gpis_hit { hit: true, t: c.t, point: c.point.into(), normal: c.normal.into(), gradient: c.gradient.into(), local: (&c.local).into() },
            Ok(Trace::Miss | Trace::Exhausted { .. }) => mf_gpis_hit { hit: false, t: 0.0, point: zero, normal: zero, gradient: zero, local: mf_local_params::NONE },
            Err(e) => return Err(e.into()),
        };
        Ok(())
    })
}

/// The body of [`mf_gpis_trace`] once its arguments are checked: the start state (a Renewal+
/// start gradient checked against the field's local prior first) and the march.
#[allow(clippy::too_many_arguments)]
fn trace_with_field<F: MediumField>(
    gpis: &GpisSurface,
    mean: &CallbackMean,
    field: &F,
    origin: DVec3,
    d: DVec3,
    t_max: f64,
    start: &mf_gpis_start,
    seed: u64,
) -> macrofacet::error::Result<Trace> {
    let state = match start.kind {
        MF_GPIS_START_FREE => StartState::Uncorrelated,
        MF_GPIS_START_ON_SURFACE => {
            let grad = DVec3::from(start.gradient);
            if !grad.is_finite() {
                return Err(Error::new(ErrorKind::InvalidArgument, format!("start.gradient must be finite, got {grad}")));
            }
            let remember = gpis.memory == macrofacet_gpis::Memory::RenewalPlus;
            if remember {
                gpis.check_start_gradient(mean, field, origin, grad)?;
            }
            StartState::OnSurface { gradient: remember.then_some(grad) }
        }
        other => {
            return Err(Error::new(
                ErrorKind::InvalidArgument,
                format!("start.kind must be MF_GPIS_START_FREE or MF_GPIS_START_ON_SURFACE, got {other}"),
            ))
        }
    };
    let mut rng = Pcg32::new(seed, 0x6d66_6770_6973); // "mfgpis"
    gpis.trace(mean, field, origin, d, t_max, &state, &mut || rng.next_f64())
}

/// Specular reflection at a crossing: `wi` (pointing away, `wi = -d`) about the unit `normal`,
/// with the field's parameters there (`*local`, as the hit reported them; NULL: the GPIS's own):
/// their `reflectance_scale` scales the reflectance. The result's `pdf` is 0: the reflection is
/// a delta, so it takes no part in MIS. `valid` is false when `wi` lies behind the normal.
///
/// # Safety
/// Pointers must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mf_gpis_scatter(
    gpis: *const mf_gpis,
    local: *const mf_local_params,
    wi: mf_vec3,
    normal: mf_vec3,
    out_sample: *mut mf_phase_sample_result,
) -> mf_status {
    boundary(|| {
        let g = arg(gpis, "gpis")?;
        let wi = check_direction("wi", wi.into())?;
        let n = check_direction("normal", normal.into())?;
        // SAFETY: NULL or a valid mf_local_params, as the caller promises.
        let local = match unsafe { local.as_ref() } {
            None => LocalParams::default(),
            Some(l) => LocalParams::try_from(l)?,
        };
        let reflected = g.inner.reflect(&local, wi, n)?;
        let slot = out(out_sample, "out_sample")?;
        let zero = mf_vec3 { x: 0.0, y: 0.0, z: 0.0 };
        *slot = match reflected {
            Some((wo, w)) => mf_phase_sample_result { wo: wo.into(), weight: mf_rgb { r: w[0], g: w[1], b: w[2] }, pdf: 0.0, valid: true },
            None => mf_phase_sample_result { wo: zero, weight: mf_rgb { r: 0.0, g: 0.0, b: 0.0 }, pdf: 0.0, valid: false },
        };
        Ok(())
    })
}
