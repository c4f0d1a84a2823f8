//! The C ABI: a thin layer over the safe core, modelled on rustls-ffi.
//!
//! Conventions (also in the README, "FFI conventions"):
//! - Every function returns an [`mf_status`]; `MF_OK` is 0, errors have their own range (7100+).
//!   The message of the last failing call on the calling thread is available through
//!   [`mf_last_error_message`].
//! - Objects are opaque handles created by `*_new` and released by `*_free`; `*_free(NULL)` is a
//!   no-op. Inputs come first, out-parameters last; out-parameters are written only on success.
//! - `mf_medium` handles are immutable and may be shared by any number of threads. `mf_params` is
//!   a builder owned by one thread at a time.
//! - Directions are world-space unit vectors; the caller passes the local frame (geometric normal
//!   and tangent) of each event. Phase functions take `wi` and `wo` pointing away from the event
//!   (`wi = -d` for a ray travelling along `d`); free-flight calls take the propagation direction.
//! - No panic crosses the boundary: every export runs inside `catch_unwind`.

#![allow(non_camel_case_types)]
// `!(x > 0.0)` is used on purpose, as in the core: unlike `x <= 0.0` it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod field;
mod gpis;
mod medium;
mod ndf;
mod params;
mod surface;
mod track;

pub use field::*;
pub use gpis::*;
pub use medium::*;
pub use ndf::*;
pub use params::*;
pub use surface::*;
pub use track::*;

use macrofacet::error::{Error, ErrorKind};
use std::cell::RefCell;
use std::ffi::{c_char, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};

/// Major version of the library and of this header.
pub const MF_VERSION_MAJOR: u32 = 0;
/// Minor version.
pub const MF_VERSION_MINOR: u32 = 1;
/// Patch version.
pub const MF_VERSION_PATCH: u32 = 0;

/// The result of every call. `MF_OK` is zero; errors occupy 7100–7199.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum mf_status {
    MF_OK = 0,
    /// A required pointer argument was NULL.
    MF_ERROR_NULL_POINTER = 7101,
    /// A query argument was NaN, infinite, not a unit vector or outside [0, 1).
    MF_ERROR_INVALID_ARGUMENT = 7102,
    /// A parameter name that the object does not take.
    MF_ERROR_UNKNOWN_PARAMETER = 7103,
    /// A parameter of the wrong type.
    MF_ERROR_WRONG_TYPE = 7104,
    /// A required parameter is missing, or two exclusive ones were both given.
    MF_ERROR_MISSING_PARAMETER = 7105,
    /// A parameter value outside its domain.
    MF_ERROR_INVALID_VALUE = 7106,
    /// A string argument was not valid UTF-8.
    MF_ERROR_INVALID_UTF8 = 7107,
    /// A host callback returned a non-zero code; the message gives it.
    MF_ERROR_CALLBACK = 7108,
    /// An internal error (a caught panic): please report it.
    MF_ERROR_INTERNAL = 7199,
}

/// Generates, from one list of `variant => message`, the table [`mf_status::ALL`], the message of
/// each status and the lookup of a C integer. The values are written once, in the enum above
/// (cbindgen reads the enum as written: it does not expand macros); the `match` generated here is
/// exhaustive, so a status added to the enum without a message does not compile.
macro_rules! status_messages {
    ($($variant:ident => $message:literal,)*) => {
        impl mf_status {
            /// Every status, in the order of the enum.
            pub const ALL: &'static [mf_status] = &[$(mf_status::$variant),*];

            /// The NUL-terminated description of this status (what [`mf_status_str`] returns).
            pub fn message(self) -> &'static str {
                match self {
                    $(mf_status::$variant => concat!($message, "\0"),)*
                }
            }

            /// The status whose value is `code`, if any.
            pub fn from_code(code: i32) -> Option<mf_status> {
                Self::ALL.iter().copied().find(|status| *status as i32 == code)
            }
        }
    };
}

status_messages! {
    MF_OK => "success",
    MF_ERROR_NULL_POINTER => "a required pointer argument was NULL",
    MF_ERROR_INVALID_ARGUMENT => "invalid argument (NaN, infinite, not unit length or out of range)",
    MF_ERROR_UNKNOWN_PARAMETER => "unknown parameter name",
    MF_ERROR_WRONG_TYPE => "parameter has the wrong type",
    MF_ERROR_MISSING_PARAMETER => "missing or conflicting parameters",
    MF_ERROR_INVALID_VALUE => "parameter value out of range",
    MF_ERROR_INVALID_UTF8 => "string is not valid UTF-8",
    MF_ERROR_CALLBACK => "a host callback reported a failure",
    MF_ERROR_INTERNAL => "internal error",
}

impl From<ErrorKind> for mf_status {
    fn from(kind: ErrorKind) -> Self {
        match kind {
            ErrorKind::UnknownParameter => mf_status::MF_ERROR_UNKNOWN_PARAMETER,
            ErrorKind::WrongType => mf_status::MF_ERROR_WRONG_TYPE,
            ErrorKind::MissingParameter => mf_status::MF_ERROR_MISSING_PARAMETER,
            ErrorKind::InvalidValue => mf_status::MF_ERROR_INVALID_VALUE,
            ErrorKind::InvalidArgument => mf_status::MF_ERROR_INVALID_ARGUMENT,
            ErrorKind::Callback => mf_status::MF_ERROR_CALLBACK,
        }
    }
}

/// An error of the FFI layer: a status and its message.
pub(crate) struct FfiError {
    status: mf_status,
    message: String,
}

impl From<Error> for FfiError {
    fn from(e: Error) -> Self {
        FfiError { status: e.kind.into(), message: e.message }
    }
}

impl FfiError {
    pub(crate) fn null(name: &str) -> Self {
        FfiError { status: mf_status::MF_ERROR_NULL_POINTER, message: format!("{name} must not be NULL") }
    }
}

pub(crate) type FfiResult<T> = Result<T, FfiError>;

thread_local! {
    static LAST_ERROR: RefCell<String> = const { RefCell::new(String::new()) };
}

/// Runs `body` behind the panic boundary and records the message of a failure for
/// [`mf_last_error_message`].
pub(crate) fn boundary(body: impl FnOnce() -> FfiResult<()>) -> mf_status {
    let error = match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(())) => return mf_status::MF_OK,
        Ok(Err(e)) => e,
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            FfiError { status: mf_status::MF_ERROR_INTERNAL, message: format!("internal error: {what}") }
        }
    };
    LAST_ERROR.with(|m| *m.borrow_mut() = error.message);
    error.status
}

/// Dereferences a pointer argument, naming it in the error when NULL.
pub(crate) fn arg<'a, T>(ptr: *const T, name: &str) -> FfiResult<&'a T> {
    // SAFETY: the caller of the exported function promises that a non-NULL pointer is valid
    // for reads for the duration of the call (documented on every function).
    unsafe { ptr.as_ref() }.ok_or_else(|| FfiError::null(name))
}

/// Checks that an out-parameter is non-NULL before any work is done.
pub(crate) fn out<'a, T>(ptr: *mut T, name: &str) -> FfiResult<&'a mut T> {
    // SAFETY: as for `arg`, for writes.
    unsafe { ptr.as_mut() }.ok_or_else(|| FfiError::null(name))
}

/// Moves `value` to the heap and returns the opaque handle the `*_new` functions hand out.
pub(crate) fn into_handle<T>(value: T) -> *mut T {
    Box::into_raw(Box::new(value))
}

/// Releases a handle from [`into_handle`]; NULL is a no-op (the `*_free` convention).
///
/// # Safety
/// `handle` must be NULL or come from `into_handle::<T>` and not have been freed.
pub(crate) unsafe fn free_handle<T>(handle: *mut T) {
    if !handle.is_null() {
        // SAFETY: created by Box::into_raw in into_handle, freed once (caller contract).
        let _ = catch_unwind(AssertUnwindSafe(|| drop(unsafe { Box::from_raw(handle) })));
    }
}

/// Borrows a NUL-terminated UTF-8 string argument.
pub(crate) fn str_arg<'a>(ptr: *const c_char, name: &str) -> FfiResult<&'a str> {
    if ptr.is_null() {
        return Err(FfiError::null(name));
    }
    // SAFETY: non-NULL and, per the documented contract, NUL-terminated and valid for the call.
    unsafe { CStr::from_ptr(ptr) }.to_str().map_err(|_| FfiError {
        status: mf_status::MF_ERROR_INVALID_UTF8,
        message: format!("{name} is not valid UTF-8"),
    })
}

/// The library version as a static NUL-terminated string, e.g. `"0.1.0"`.
#[no_mangle]
pub extern "C" fn mf_version() -> *const c_char {
    concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr().cast()
}

/// A static, NUL-terminated description of a status code (never NULL; unknown codes give
/// `"unknown status"`). Takes the code as an integer: C may pass any value, and an out-of-range
/// value of a Rust enum would be undefined behaviour.
#[no_mangle]
pub extern "C" fn mf_status_str(status: i32) -> *const c_char {
    mf_status::from_code(status).map_or("unknown status\0", mf_status::message).as_ptr().cast()
}

/// Copies the message of the last failing call on this thread into `buf` (NUL-terminated,
/// truncated to `len - 1` bytes) and stores the full length (without the NUL) in `*out_len` when
/// `out_len` is not NULL. An empty string when no call has failed yet. `buf` may be NULL when
/// `len` is 0 (to query the length).
///
/// # Safety
/// `buf` must be valid for `len` bytes of writes.
#[no_mangle]
pub unsafe extern "C" fn mf_last_error_message(buf: *mut c_char, len: usize, out_len: *mut usize) -> mf_status {
    let result = catch_unwind(|| {
        LAST_ERROR.with(|m| {
            let message = m.borrow();
            let bytes = message.as_bytes();
            if len > 0 {
                if buf.is_null() {
                    return mf_status::MF_ERROR_NULL_POINTER;
                }
                let n = bytes.len().min(len - 1);
                // SAFETY: the caller promises `buf` holds `len` bytes; we write n + 1 <= len.
                unsafe {
                    std::ptr::copy_nonoverlapping(bytes.as_ptr(), buf.cast::<u8>(), n);
                    *buf.add(n) = 0;
                }
            }
            if !out_len.is_null() {
                // SAFETY: non-NULL out-pointer supplied by the caller.
                unsafe { *out_len = bytes.len() };
            }
            mf_status::MF_OK
        })
    });
    result.unwrap_or(mf_status::MF_ERROR_INTERNAL)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every status of the table maps back from its value and has its own description;
    /// values outside the table are "unknown status".
    #[test]
    fn status_table_round_trips() {
        let message = |code: i32| unsafe { CStr::from_ptr(mf_status_str(code)) }.to_str().unwrap();
        for (i, status) in mf_status::ALL.iter().enumerate() {
            assert_eq!(mf_status::from_code(*status as i32), Some(*status));
            assert!(status.message().ends_with('\0'));
            assert_ne!(message(*status as i32), "unknown status");
            for other in &mf_status::ALL[..i] {
                assert_ne!(message(*status as i32), message(*other as i32), "{status:?} and {other:?}");
            }
        }
        for code in [-1, 1, 7100, 7109, 7198, 7200, i32::MIN, i32::MAX] {
            assert_eq!(message(code), "unknown status");
        }
    }
}
