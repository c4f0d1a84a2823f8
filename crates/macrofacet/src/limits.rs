//! The domain of the medium parameters. Inside it every derived quantity is a finite, normal
//! `f64` and every query answers with finite numbers; outside it the constructors refuse the
//! value and say why (issue 9 item 8: `sigma = 1e308` was accepted and gave an infinite shell
//! top). The bounds are wide: each is where `f64` stops or where the medium stops changing.

use crate::error::{Error, ErrorKind, Result};

/// `sigma` (scene units). Products of up to four factors `σ^±1` and `α^±1` — the kernel's
/// derivative covariances `σ² w_i w_j` with `w_i = α_i²/(2σ²)` (seeds/000 Eq. 4,
/// seeds/004 Eq. 5–6), the flake density `|f|/σ²` deep inside (seeds/000 Eq. 13) — stay within 1e±216.
pub const SIGMA_RANGE: (f64, f64) = (1e-50, 1e50);

/// `shell_extent` `k` of the medium (the shell's top at `kσ`). Above `f ≈ 38.6 σ` the flake
/// density `φ/Φ` (seeds/000 Eq. 13) underflows to 0 and `Φ(−k)` falls below `1e-300`, so a larger
/// `k` only adds empty space to march through; below 1e-6 the cut is the mean surface itself
/// (`1 − Φ(k) = 0.5 − 4e-7`), and `kσ` stays a normal number for every `sigma` of the domain.
pub const SHELL_EXTENT_RANGE: (f64, f64) = (1e-6, 40.0);

/// The conductor index `eta + i k` per channel. Measured metals have `0.03 < eta < 10` and
/// `k < 20` (seeds: the presets of `fresnel.rs`); the closed-form Fresnel squares `eta² + k²`
/// twice, which stays finite and accurate far beyond, up to 1e6.
pub const ETA_RANGE: (f64, f64) = (1e-6, 1e6);
/// See [`ETA_RANGE`]; `k = 0` (a dielectric-like index) is allowed.
pub const K_RANGE: (f64, f64) = (0.0, 1e6);

/// `alpha_u`, `alpha_v` (and `alpha_z` when not 0). A lobe narrower than 1e-6 rad is a mirror to
/// any renderer (an `f32` unit direction resolves 6e-8 rad; the lobe's density `~1/α²` is then
/// 1e12); above 1e6 every normal is within 1e-6 rad of its `α → ∞` limit (the horizon for
/// Beckmann and GGX, an isotropic spread for gpss). Inside, the NDFs, samplers and densities
/// are finite and agree (measured down to 1e-100 and up to 1e50, where `1/α²` and `α⁴` begin to
/// meet the limits of `f64`), and `α^±4 ≤ 1e24` leaves [`SIGMA_RANGE`]'s products finite.
pub const ROUGHNESS_RANGE: (f64, f64) = (1e-6, 1e6);

/// Smallest positive `alpha_z`. Below it the generalized NDF (seeds/000 Eq. 38) equals Beckmann's
/// to 5e-11 relative (measured at 1e-8), and its closed form overflows below `≈ 1e-150`
/// (`α_z²` underflows): give 0 for a height field.
pub const ALPHA_Z_MIN: f64 = 1e-8;

pub fn out_of_domain(message: String) -> Error {
    Error::new(ErrorKind::InvalidValue, message)
}

/// `value` within `[lo, hi]` (finite); otherwise an error: "`subject` = value lies outside
/// [lo, hi]: `why`". `subject` names the parameter, e.g. `parameter "sigma"`.
pub fn check_range(subject: &str, value: f64, (lo, hi): (f64, f64), why: &str) -> Result<f64> {
    if value >= lo && value <= hi {
        Ok(value)
    } else {
        Err(out_of_domain(format!("{subject} = {value:e} lies outside [{lo:e}, {hi:e}]: {why}")))
    }
}

/// `sigma` within [`SIGMA_RANGE`]; `subject` as in [`check_range`].
pub(crate) fn check_sigma(subject: &str, sigma: f64) -> Result<f64> {
    check_range(subject, sigma, SIGMA_RANGE, "sigma^2 and 1/sigma^2 must stay far from the limits of f64")
}

/// The medium's `shell_extent` within [`SHELL_EXTENT_RANGE`].
pub(crate) fn check_shell_extent(k: f64) -> Result<f64> {
    check_range("parameter \"shell_extent\"", k, SHELL_EXTENT_RANGE, "above 38.6 sigma the flake density is 0 in f64, below 1e-6 the top is the mean surface")
}

/// One channel of a conductor's `eta` or `k` within [`ETA_RANGE`] / [`K_RANGE`].
pub(crate) fn check_conductor_index(name: &str, channel: usize, value: f64) -> Result<f64> {
    let range = if name == "eta" { ETA_RANGE } else { K_RANGE };
    check_range(&format!("parameter \"{name}\" (channel {channel})"), value, range, "metals have 0.03 < eta < 10 and k < 20")
}

/// A roughness `alpha_u` / `alpha_v` within [`ROUGHNESS_RANGE`]; `subject` as in [`check_range`].
pub(crate) fn check_roughness(subject: &str, alpha: f64) -> Result<f64> {
    check_range(subject, alpha, ROUGHNESS_RANGE, "below 1e-6 the medium is a mirror, above 1e6 its normals no longer change")
}

/// `alpha_z`: 0 (a height field) or within `[ALPHA_Z_MIN, ROUGHNESS_RANGE.1]`.
pub(crate) fn check_alpha_z(subject: &str, alpha_z: f64) -> Result<f64> {
    if alpha_z == 0.0 {
        return Ok(0.0);
    }
    check_range(subject, alpha_z, (ALPHA_Z_MIN, ROUGHNESS_RANGE.1), "give 0 for a height field (below 1e-8 the NDF is Beckmann's)")
}
