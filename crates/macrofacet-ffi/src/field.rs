//! `mf_field`: spatially varying medium parameters (seeds/004 Sec. 6.1) that the host evaluates —
//! grids, textures, procedures — handed to the tracking calls (see [`macrofacet::field`]). The library
//! asks for the parameters at tentative collisions and for their bounds along each tracked
//! segment; a collision reports the parameters where it happened, and the `_local` phase calls
//! take them.

use super::medium::{frame, local_direction, mf_frame, mf_medium, mf_phase_sample_result, mf_phase_value, mf_rgb, mf_vec3, phase_sample_with, rgb};
use super::surface::mf_surface_point;
use super::{arg, boundary, free_handle, into_handle, mf_status, out, FfiError, FfiResult};
use macrofacet::error::{Error, ErrorKind, Result};
use macrofacet::field::{LocalParams, MediumField, ParamBounds};
use macrofacet::frame::Frame;
use macrofacet::surface::SurfacePoint;
use macrofacet::{MacrofacetMedium, PHASE_SAMPLE_DIMENSIONS};
use glam::{DMat3, DVec3};
use std::ffi::c_void;

/// [`mf_local_params::set`] / [`mf_param_bounds::set`]: `sigma` is given.
pub const MF_LOCAL_SIGMA: u32 = 1;
/// `alpha` is given (`alpha_u`, `alpha_v`, `alpha_z` in the local frame).
pub const MF_LOCAL_ALPHA: u32 = 2;
/// `anisotropy` is given (gpss media only; bounds of it go in `alpha_lo`/`alpha_hi`).
pub const MF_LOCAL_ANISOTROPY: u32 = 4;
/// `reflectance_scale` is given.
pub const MF_LOCAL_REFLECTANCE_SCALE: u32 = 8;

/// The medium's parameters at one point; fields whose bit is not in `set` keep the medium's
/// value.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct mf_local_params {
    /// Bits `MF_LOCAL_*`.
    pub set: u32,
    /// Standard deviation of the heights (scene units, `> 0`).
    pub sigma: f64,
    /// Roughness along the local tangent, bitangent and normal (`x = alpha_u`, `y = alpha_v`,
    /// `z = alpha_z`); Beckmann and GGX read `x`, `y`. `alpha_u, alpha_v > 0`, `alpha_z >= 0`.
    pub alpha: mf_vec3,
    /// The kernel's local anisotropy `Σ` of seeds/004 Eq. 25 in world space, a symmetric
    /// positive-definite matrix with the lengthscales² on its axes, as `xx, yy, zz, xy, xz, yz`
    /// (Mitsuba's SGGX order); the roughness matrix is `2 σ² Σ⁻¹` in the local frame.
    pub anisotropy: [f64; 6],
    /// Multiplies the flakes' reflectance per channel (the product must stay within `[0, 1]`).
    pub reflectance_scale: mf_rgb,
}

/// Bounds of the parameters along a segment (for majorants). With `MF_LOCAL_SIGMA`:
/// `sigma_lo <= σ <= sigma_hi`; with `MF_LOCAL_ALPHA` (also for `MF_LOCAL_ANISOTROPY`): every
/// roughness the NDF sees — each `alpha` component, or `√λ` over the eigenvalues `λ` of
/// `2σ²Σ⁻¹` — within `[alpha_lo, alpha_hi]`. A field must bound every parameter it varies.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct mf_param_bounds {
    pub set: u32,
    pub sigma_lo: f64,
    pub sigma_hi: f64,
    pub alpha_lo: f64,
    pub alpha_hi: f64,
}

/// The host's parameters at `p`, where the mean surface is `*point`: writes `*out` and returns
/// 0, or a non-zero code on failure (the tracking call then fails with `MF_ERROR_CALLBACK`).
pub type mf_field_at_fn = Option<unsafe extern "C" fn(user_data: *mut c_void, p: mf_vec3, point: *const mf_surface_point, out: *mut mf_local_params) -> i32>;

/// The host's bounds along `p + s d`, `s ∈ [0, length]`: writes `*out` and returns 0, or a
/// non-zero code on failure.
pub type mf_field_bounds_fn = Option<unsafe extern "C" fn(user_data: *mut c_void, p: mf_vec3, d: mf_vec3, length: f64, out: *mut mf_param_bounds) -> i32>;

/// A field implemented by the host. Both callbacks get the `user_data` of the tracking call.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct mf_field_callbacks {
    /// Required.
    pub at: mf_field_at_fn,
    /// Required.
    pub bounds: mf_field_bounds_fn,
    /// The largest `σ` anywhere (the region's top face is at `shell_extent × sigma_max`), within
    /// the domain of `sigma` (`[1e-50, 1e50]`); 0 when `σ` does not vary.
    pub sigma_max: f64,
}

/// A field of local parameters. Immutable and safe to share between threads (its callbacks must
/// then be thread-safe, or be given per-thread `user_data`).
pub struct mf_field {
    at: unsafe extern "C" fn(*mut c_void, mf_vec3, *const mf_surface_point, *mut mf_local_params) -> i32,
    bounds: unsafe extern "C" fn(*mut c_void, mf_vec3, mf_vec3, f64, *mut mf_param_bounds) -> i32,
    sigma_max: Option<f64>,
}

/// A field with the `user_data` of one call.
pub(crate) struct CallbackField<'a> {
    field: &'a mf_field,
    user_data: *mut c_void,
}

impl<'a> CallbackField<'a> {
    pub(crate) fn new(field: &'a mf_field, user_data: *mut c_void) -> Self {
        CallbackField { field, user_data }
    }
}

fn callback_failed(what: &str, code: i32) -> Error {
    Error::new(ErrorKind::Callback, format!("the field's {what} callback returned {code}"))
}

impl mf_local_params {
    /// Nothing set: the medium's own parameters.
    pub const NONE: mf_local_params = mf_local_params {
        set: 0,
        sigma: 0.0,
        alpha: mf_vec3 { x: 0.0, y: 0.0, z: 0.0 },
        anisotropy: [0.0; 6],
        reflectance_scale: mf_rgb { r: 0.0, g: 0.0, b: 0.0 },
    };
}

impl TryFrom<&mf_local_params> for LocalParams {
    type Error = Error;
    fn try_from(p: &mf_local_params) -> Result<LocalParams> {
        let known = MF_LOCAL_SIGMA | MF_LOCAL_ALPHA | MF_LOCAL_ANISOTROPY | MF_LOCAL_REFLECTANCE_SCALE;
        if p.set & !known != 0 {
            return Err(Error::new(ErrorKind::InvalidArgument, format!("local parameters: unknown bits in set = {:#x}", p.set)));
        }
        let has = |bit: u32| p.set & bit != 0;
        let [xx, yy, zz, xy, xz, yz] = p.anisotropy;
        let local = LocalParams {
            sigma: has(MF_LOCAL_SIGMA).then_some(p.sigma),
            alpha: has(MF_LOCAL_ALPHA).then(|| DVec3::from(p.alpha)),
            anisotropy: has(MF_LOCAL_ANISOTROPY).then(|| DMat3::from_cols(DVec3::new(xx, xy, xz), DVec3::new(xy, yy, yz), DVec3::new(xz, yz, zz))),
            reflectance_scale: has(MF_LOCAL_REFLECTANCE_SCALE).then_some([p.reflectance_scale.r, p.reflectance_scale.g, p.reflectance_scale.b]),
        };
        local.validate("local parameters")?;
        Ok(local)
    }
}

impl From<&LocalParams> for mf_local_params {
    fn from(l: &LocalParams) -> mf_local_params {
        let mut p = mf_local_params::NONE;
        if let Some(s) = l.sigma {
            p.set |= MF_LOCAL_SIGMA;
            p.sigma = s;
        }
        if let Some(a) = l.alpha {
            p.set |= MF_LOCAL_ALPHA;
            p.alpha = a.into();
        }
        if let Some(m) = l.anisotropy {
            p.set |= MF_LOCAL_ANISOTROPY;
            p.anisotropy = [m.x_axis.x, m.y_axis.y, m.z_axis.z, m.y_axis.x, m.z_axis.x, m.z_axis.y];
        }
        if let Some(r) = l.reflectance_scale {
            p.set |= MF_LOCAL_REFLECTANCE_SCALE;
            p.reflectance_scale = mf_rgb { r: r[0], g: r[1], b: r[2] };
        }
        p
    }
}

impl MediumField for CallbackField<'_> {
    fn at(&self, p: DVec3, point: &SurfacePoint) -> Result<LocalParams> {
        let c_point: mf_surface_point = (*point).into();
        let mut out = mf_local_params::NONE;
        // SAFETY: the host registered a callable function; it writes one mf_local_params.
        let code = unsafe { (self.field.at)(self.user_data, p.into(), &c_point, &mut out) };
        if code != 0 {
            return Err(callback_failed("at", code));
        }
        LocalParams::try_from(&out).map_err(|e| Error::new(e.kind, format!("the field at {p}: {}", e.message)))
    }

    fn bounds(&self, p: DVec3, d: DVec3, length: f64) -> Result<ParamBounds> {
        let mut out = mf_param_bounds { set: 0, sigma_lo: f64::NAN, sigma_hi: f64::NAN, alpha_lo: f64::NAN, alpha_hi: f64::NAN };
        // SAFETY: as for `at`.
        let code = unsafe { (self.field.bounds)(self.user_data, p.into(), d.into(), length, &mut out) };
        if code != 0 {
            return Err(callback_failed("bounds", code));
        }
        if out.set & !(MF_LOCAL_SIGMA | MF_LOCAL_ALPHA) != 0 {
            return Err(Error::new(ErrorKind::InvalidArgument, format!("the field's bounds: set must combine MF_LOCAL_SIGMA and MF_LOCAL_ALPHA, got {:#x}", out.set)));
        }
        Ok(ParamBounds {
            sigma: (out.set & MF_LOCAL_SIGMA != 0).then_some([out.sigma_lo, out.sigma_hi]),
            alpha: (out.set & MF_LOCAL_ALPHA != 0).then_some([out.alpha_lo, out.alpha_hi]),
        })
    }

    fn sigma_max(&self) -> Option<f64> {
        self.field.sigma_max
    }
}

/// Creates a host-implemented field (see [`mf_field_callbacks`]).
///
/// # Safety
/// `callbacks` must be NULL or valid; `out_field` NULL or valid for writes.
#[no_mangle]
pub unsafe extern "C" fn mf_field_new_callbacks(callbacks: *const mf_field_callbacks, out_field: *mut *mut mf_field) -> mf_status {
    boundary(|| {
        let c = arg(callbacks, "callbacks")?;
        let slot = out(out_field, "out_field")?;
        let at = c.at.ok_or_else(|| FfiError::null("callbacks->at"))?;
        let bounds = c.bounds.ok_or_else(|| FfiError::null("callbacks->bounds"))?;
        let sigma_max = match c.sigma_max {
            0.0 => None,
            // Within the domain of sigma: beyond it every value would be refused where the field
            // is evaluated (found by fuzzing: sigma_max = DBL_MAX made the first segment
            // infinitely long, with a lower bound of f that lost its slope).
            s if s > 0.0 && s.is_finite() => Some(macrofacet::limits::check_range("callbacks->sigma_max", s, macrofacet::limits::SIGMA_RANGE, "the largest sigma must lie in the domain of sigma")?),
            s => return Err(Error::new(ErrorKind::InvalidArgument, format!("callbacks->sigma_max must be 0 (sigma does not vary) or finite and > 0, got {s}")).into()),
        };
        *slot = into_handle(mf_field { at, bounds, sigma_max });
        Ok(())
    })
}

/// Releases a field; NULL is a no-op.
///
/// # Safety
/// `field` must be NULL or a pointer from [`mf_field_new_callbacks`], not yet freed and not in
/// use by another thread.
#[no_mangle]
pub unsafe extern "C" fn mf_field_free(field: *mut mf_field) {
    free_handle(field);
}

/// The medium at an event with local parameters, built in `slot`; without them (NULL) the medium
/// itself, borrowed. (A slot, not a returned `Cow`: the medium is 736 bytes, and moving a result
/// holding it cost every phase call of a stationary medium, their hot path, a copy.)
fn localized<'m>(m: &'m MacrofacetMedium, local: *const mf_local_params, frame: &Frame, slot: &'m mut Option<MacrofacetMedium>) -> FfiResult<&'m MacrofacetMedium> {
    if local.is_null() {
        return Ok(m);
    }
    // SAFETY: non-NULL, and the caller promises a valid mf_local_params.
    let local = LocalParams::try_from(unsafe { &*local })?;
    Ok(slot.insert(m.localized(&local, frame)?))
}

/// [`super::medium::mf_phase_sample`] at an event whose local parameters are `*local` (as a
/// collision reported them; NULL: the medium's own).
///
/// # Safety
/// Pointers must be NULL or valid; `u` must hold `MF_PHASE_SAMPLE_DIMENSIONS` doubles.
#[no_mangle]
pub unsafe extern "C" fn mf_phase_sample_local(
    medium: *const mf_medium,
    local: *const mf_local_params,
    frame_: *const mf_frame,
    wi: mf_vec3,
    u: *const f64,
    out_sample: *mut mf_phase_sample_result,
) -> mf_status {
    boundary(|| {
        let m = arg(medium, "medium")?;
        let first = arg(u, "u")?;
        let fr = frame(arg(frame_, "frame")?)?;
        let mut slot = None;
        let medium = localized(&m.inner, local, &fr, &mut slot)?;
        // SAFETY: the caller promises MF_PHASE_SAMPLE_DIMENSIONS readable doubles at `u`.
        let u: [f64; PHASE_SAMPLE_DIMENSIONS] = unsafe { std::slice::from_raw_parts(first, PHASE_SAMPLE_DIMENSIONS) }.try_into().expect("length");
        let result = phase_sample_with(medium, &fr, wi, u)?;
        *out(out_sample, "out_sample")? = result;
        Ok(())
    })
}

/// [`super::medium::mf_phase_eval_pdf`] at an event whose local parameters are `*local` (NULL:
/// the medium's own).
///
/// # Safety
/// Pointers must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mf_phase_eval_pdf_local(
    medium: *const mf_medium,
    local: *const mf_local_params,
    frame_: *const mf_frame,
    wi: mf_vec3,
    wo: mf_vec3,
    out_value: *mut mf_phase_value,
) -> mf_status {
    boundary(|| {
        let m = arg(medium, "medium")?;
        let fr = frame(arg(frame_, "frame")?)?;
        let mut slot = None;
        let medium = localized(&m.inner, local, &fr, &mut slot)?;
        let (wi, wo) = (local_direction(&fr, "wi", wi)?, local_direction(&fr, "wo", wo)?);
        let (value, pdf) = medium.phase.eval_pdf(wi, wo);
        *out(out_value, "out_value")? = mf_phase_value { value: rgb(value), pdf };
        Ok(())
    })
}
