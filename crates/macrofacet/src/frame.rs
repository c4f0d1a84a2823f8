//! The local shading frame of a medium event.
//!
//! Convention (design notes, "Local frame"): the geometric normal `n` — the gradient of the mean
//! signed distance — is local `+z`; the host's tangent, projected orthogonal to `n`, is local `+x`
//! and carries the `alpha_u` roughness; local `+y = z × x` carries `alpha_v`.

use crate::error::{Error, ErrorKind, Result};
use glam::DVec3;

/// An orthonormal frame `(s, t, n)`; `to_local` and `to_world` are exact inverses up to rounding.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub s: DVec3,
    pub t: DVec3,
    pub n: DVec3,
}

impl Frame {
    /// Builds the frame from a normal and a tangent hint. Neither needs to be normalised; the
    /// tangent is made orthogonal to `n` (Gram–Schmidt). A tangent parallel to `n` (or zero) falls
    /// back to an arbitrary orthonormal completion, which is correct for isotropic roughness.
    pub fn from_normal_tangent(n: DVec3, tangent: DVec3) -> Result<Frame> {
        check_finite_vector("normal", n)?;
        check_finite_vector("tangent", tangent)?;
        let n = rescaled(n).try_normalize().ok_or_else(|| {
            Error::new(ErrorKind::InvalidArgument, "the normal must not be the zero vector")
        })?;
        // A tangent (nearly) parallel to n leaves only rounding noise after the projection;
        // normalising that noise would give a vector that is not orthogonal to n. (Lengths
        // compared squared: |projection| > 1e-6 |tangent|, without two square roots.)
        let tangent = rescaled(tangent);
        let projected = tangent - n * n.dot(tangent);
        let s = if projected.length_squared() > 1e-12 * tangent.length_squared() {
            rescaled(projected).normalize()
        } else {
            n.any_orthonormal_vector()
        };
        Ok(Frame { s, t: n.cross(s), n })
    }

    /// The frame whose `n` is world `+z`: local and world coordinates coincide.
    pub fn identity() -> Frame {
        Frame { s: DVec3::X, t: DVec3::Y, n: DVec3::Z }
    }

    pub fn to_local(&self, v: DVec3) -> DVec3 {
        DVec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    pub fn to_world(&self, v: DVec3) -> DVec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

/// 2^-500 and 2^500: vectors whose largest component lies between need no rescaling.
const NO_RESCALE_MIN: f64 = 3.054936363499605e-151;
const NO_RESCALE_MAX: f64 = 3.273390607896142e150;

/// `v` scaled by a power of two (exactly) to bring its largest component into `[1, 2)` when that
/// lies outside `[2^-500, 2^500]` (otherwise `v` itself), which leaves its direction unchanged. Normalising then squares numbers near 1: `|v|²` of a vector as short
/// as 1e-159 is subnormal (a normal of length 1e-159 gave world directions of length 0.999999,
/// issue 9 item 5) and that of a vector longer than 1e154 overflows.
pub(crate) fn rescaled(v: DVec3) -> DVec3 {
    let largest = v.abs().max_element();
    // Between 2^-500 and 2^500 nothing under- or overflows, and scaling by a power of two
    // commutes exactly with normalising: the same result without the log2 (a hot path).
    if largest == 0.0 || !largest.is_finite() || (NO_RESCALE_MIN..=NO_RESCALE_MAX).contains(&largest) {
        return v;
    }
    // 2^(−exponent of largest): exact, and no overflow for subnormal `largest` (2^1074 would).
    let exponent = (largest.log2().floor() as i32).clamp(-1022, 1023);
    v * 2f64.powi(-exponent)
}

/// `(robust_length(v), rescaled(v).try_normalize())`, bit for bit, with one square root where
/// nothing needs rescaling (the common case; `try_normalize` is `v` times `1 / |v|`).
pub(crate) fn length_and_direction(v: DVec3) -> (f64, Option<DVec3>) {
    let largest = v.abs().max_element();
    if (NO_RESCALE_MIN..=NO_RESCALE_MAX).contains(&largest) {
        let length = v.length();
        return (length, Some(v * (1.0 / length)));
    }
    (robust_length(v), rescaled(v).try_normalize())
}

/// `|v|` without the overflow or underflow of `|v|²` beyond 1e±154.
pub(crate) fn robust_length(v: DVec3) -> f64 {
    let largest = v.abs().max_element();
    if largest == 0.0 || !largest.is_finite() || (NO_RESCALE_MIN..=NO_RESCALE_MAX).contains(&largest) {
        return v.length();
    }
    largest * (v / largest).length()
}

/// Rejects NaN or infinite components; the message names `name`.
pub fn check_finite_vector(name: &str, v: DVec3) -> Result<DVec3> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::new(ErrorKind::InvalidArgument, format!("{name} must be finite, got {v}")))
    }
}

/// Rejects vectors that are not finite and unit length (within `1e-6`, f32 round-off of a host).
/// Returns the vector renormalised in f64.
/// (Inlined, with the messages out of line: every call of the C ABI checks its directions.)
#[inline]
pub fn check_direction(name: &str, v: DVec3) -> Result<DVec3> {
    unit_direction(v).ok_or_else(|| not_a_direction(name, v))
}

/// [`check_direction`] without the message: `None` where it fails. For hot paths that build
/// their error apart ([`not_a_direction`]): a `Result` of a vector, moved through callers,
/// was copied in odd-sized pieces that stalled the loads after them (half the time of the
/// tracking calls' query check: 2.5 % of the fuzzy sphere's time in bench/gpis_compare.xml, perf).
#[inline]
pub fn unit_direction(v: DVec3) -> Option<DVec3> {
    let len = v.length();
    // (A NaN or infinite component fails the comparison.)
    ((len - 1.0).abs() <= 1e-6).then(|| v / len)
}

/// The error of [`check_direction`] for `v`, which [`unit_direction`] refused.
#[cold]
#[inline(never)]
pub fn not_a_direction(name: &str, v: DVec3) -> Error {
    if let Err(e) = check_finite_vector(name, v) {
        return e;
    }
    Error::new(ErrorKind::InvalidArgument, format!("{name} must be a unit vector, got {v} (length {})", v.length()))
}
