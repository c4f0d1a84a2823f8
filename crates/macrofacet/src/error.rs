//! Errors of the safe core. Every constructor validates its input and returns one of these instead
//! of panicking; the C ABI maps [`ErrorKind`] onto its status enum.

use std::fmt;

/// What went wrong, coarse enough to map one-to-one onto a C status code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorKind {
    /// A parameter name that the object does not take.
    UnknownParameter,
    /// A parameter given with the wrong type (e.g. a string where a number is expected).
    WrongType,
    /// A required parameter is absent, or two parameters that exclude each other are both set.
    MissingParameter,
    /// A value outside its domain: NaN, infinite, negative, zero where positive is required,
    /// or an unknown enumeration value.
    InvalidValue,
    /// A query argument (direction, signed distance, random number) is NaN, infinite or
    /// not normalised.
    InvalidArgument,
    /// A host callback (e.g. a mean surface's) reported a failure.
    Callback,
}

/// An error with a message that names the parameter or argument at fault.
#[derive(Clone, Debug, PartialEq)]
pub struct Error {
    pub kind: ErrorKind,
    pub message: String,
}

impl Error {
    pub fn new(kind: ErrorKind, message: impl Into<String>) -> Self {
        Error { kind, message: message.into() }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Error {}

pub type Result<T> = std::result::Result<T, Error>;

/// Checks that `value` is finite and `> 0` (or `>= 0` when `allow_zero`); the message names `name`.
pub(crate) fn check_positive(name: &str, value: f64, allow_zero: bool) -> Result<f64> {
    let ok = value.is_finite() && (value > 0.0 || (allow_zero && value == 0.0));
    if ok {
        Ok(value)
    } else {
        let bound = if allow_zero { ">= 0" } else { "> 0" };
        Err(Error::new(
            ErrorKind::InvalidValue,
            format!("parameter \"{name}\" must be finite and {bound}, got {value}"),
        ))
    }
}
