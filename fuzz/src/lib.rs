//! Shared pieces of the fuzz targets in `fuzz_targets/`: turning fuzz bytes into ABI arguments
//! ([`input`]), building media, gpis and distribution handles from them ([`build`]) and mean
//! surfaces ([`surface`]), the host's callback surfaces and fields ([`host`]), the property
//! every `MF_OK` must satisfy ([`check`]) and the tracking calls checked by it ([`track`]).
//!
//! The property (README, "FFI conventions", "What `MF_OK` promises"): finite outputs, unit
//! directions (1e-6), `0 <= T <= 1`, `0 <= t <= t_max`, `pdf > 0` for valid samples,
//! `weight == eval / pdf` (relative 1e-6 where both are defined), and on any error the
//! out-parameters untouched, a message from `mf_last_error_message` and a known status.
//!
//! ## Adding an entry point
//! 1. Call it through [`check::call`] (one out-parameter) or [`check::call_array`] (a batch):
//!    they pre-fill the output with a sentinel, and on an error check that it is untouched and
//!    that the error is reported; on `MF_OK` they return the value.
//! 2. Check the value with the functions of [`check`] (`unit`, `transmittance`,
//!    `free_flight`, `phase_sample`, ...) or add one there if the new call promises something
//!    new.
//! 3. Draw its arguments with [`input::Bytes`] (edge-biased floats, near-unit directions,
//!    frames) in the target whose handle it takes (`medium_queries`, `phase`, `gpis`,
//!    `tracking`, `fields` or `ndf`), or in a
//!    new target listed in `Cargo.toml` and `scripts/fuzz.sh`.

pub mod build;
pub mod check;
pub mod host;
pub mod input;
pub mod surface;
pub mod track;
