//! `mf_params`: a parameter set filled by name from the host's scene format.

use super::{arg, boundary, free_handle, into_handle, out, str_arg, FfiError, FfiResult};
use super::mf_status;
use macrofacet::params::{ParamSet, ParamValue};
use std::ffi::c_char;

/// An ordered set of named parameters (see the README for the names a medium takes).
/// Setting a name again replaces its value. Not thread-safe: one thread at a time.
pub struct mf_params {
    pub(crate) inner: ParamSet,
}

/// Creates an empty parameter set in `*out`; release it with [`mf_params_free`].
///
/// # Safety
/// `out` must be NULL or valid for writes.
#[no_mangle]
pub unsafe extern "C" fn mf_params_new(out_params: *mut *mut mf_params) -> mf_status {
    boundary(|| {
        let slot = out(out_params, "out_params")?;
        *slot = into_handle(mf_params { inner: ParamSet::new() });
        Ok(())
    })
}

/// Releases a parameter set; NULL is a no-op.
///
/// # Safety
/// `params` must be NULL or a pointer from [`mf_params_new`] not yet freed.
#[no_mangle]
pub unsafe extern "C" fn mf_params_free(params: *mut mf_params) {
    free_handle(params);
}

fn set(params: *mut mf_params, name: *const c_char, value: FfiResult<ParamValue>) -> mf_status {
    boundary(|| {
        let params = out(params, "params")?;
        let name = str_arg(name, "name")?;
        params.inner.set(name, value?);
        Ok(())
    })
}

/// Sets a float parameter. The value is checked when the object is built (so that the error can
/// name the parameter in context), except NaN/Inf, which are rejected here.
///
/// # Safety
/// `params` must be a live handle; `name` a NUL-terminated string.
#[no_mangle]
pub unsafe extern "C" fn mf_params_set_float(params: *mut mf_params, name: *const c_char, value: f64) -> mf_status {
    let checked = if value.is_finite() {
        Ok(ParamValue::Float(value))
    } else {
        Err(FfiError { status: mf_status::MF_ERROR_INVALID_VALUE, message: format!("parameter value must be finite, got {value}") })
    };
    set(params, name, checked)
}

/// Sets an RGB parameter from three doubles.
///
/// # Safety
/// `params` must be a live handle; `name` a NUL-terminated string; `rgb` three readable doubles.
#[no_mangle]
pub unsafe extern "C" fn mf_params_set_rgb(params: *mut mf_params, name: *const c_char, rgb: *const f64) -> mf_status {
    let value = (|| {
        let first = arg(rgb, "rgb")?;
        // SAFETY: the caller promises three readable doubles at `rgb`.
        let rgb: [f64; 3] = unsafe { std::slice::from_raw_parts(first, 3) }.try_into().expect("three elements");
        if rgb.iter().all(|c| c.is_finite()) {
            Ok(ParamValue::Rgb(rgb))
        } else {
            Err(FfiError { status: mf_status::MF_ERROR_INVALID_VALUE, message: format!("rgb value must be finite, got {rgb:?}") })
        }
    })();
    set(params, name, value)
}

/// Sets a string parameter (copied).
///
/// # Safety
/// `params` must be a live handle; `name` and `value` NUL-terminated strings.
#[no_mangle]
pub unsafe extern "C" fn mf_params_set_string(params: *mut mf_params, name: *const c_char, value: *const c_char) -> mf_status {
    let value = str_arg(value, "value").map(|v| ParamValue::String(v.to_owned()));
    set(params, name, value)
}
