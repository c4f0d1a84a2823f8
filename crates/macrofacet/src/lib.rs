//! # macrofacet
//!
//! Gaussian-process statistical surfaces (GPSS) rendered as classic exponential participating
//! media — the *macrofacet theory* of Huang, Cui, Wang and Yan (seeds/000). A surface whose
//! heights are a Gaussian process becomes a shell of flakes around its mean surface, with
//! extinction `σ_t(f, d) = ρ(f) σ(d)` (seeds/000 Eq. 14/31) and a conductor phase function (seeds/000 Eq. 11–12)
//! built from a full-sphere NDF (seeds/000 Eq. 38). Nothing here realizes a Gaussian process.
//!
//! Pure maths: no I/O, no global state, and no random state kept between calls: every random
//! number comes from the caller. Routines that need a fixed count take the caller's uniforms
//! (`u`); those that need an unbounded count (tracking, GPIS realizations) take a 64-bit seed per
//! call and run [`rng::Pcg32`] from it on a fixed, documented stream (tracking:
//! [`tracking::TRACK_STREAM`]; `mf_gpis_trace`: the stream `"mfgpis"` of `src/ffi/gpis.rs`), so
//! the same arguments give the same result. All arithmetic is `f64`.
//!
//! ## Conventions (stated once, followed everywhere)
//! - **Local frame**: the geometric normal (gradient of the mean signed distance) is `+z`; the
//!   tangent is `+x` and carries `alpha_u` ([`frame::Frame`]).
//! - **Directions**: phase functions and NDF samplers take `wi`, `wo` pointing *away* from the
//!   event (as Mitsuba 3 and pbrt-v4 do); a ray travelling along `d` has `wi = -d` (Mitsuba 3's
//!   name: its `si.wi` is `-ray.d`; pbrt-v4 calls the same vector `wo`). Free-flight routines take
//!   the propagation direction `d`.
//! - **SDF sign**: `f > 0` outside / above the mean surface, `f < 0` inside.
//! - **Units**: `sigma` in scene units, roughness unitless, `alpha_i = √2 σ / l_i` (seeds/000 Eq. 4).
//! - **Spectrum**: RGB triplets ([`Rgb`]).

// `!(x > 0.0)` is used on purpose throughout: unlike `x <= 0.0` it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod error;
pub mod field;
pub mod frame;
pub mod fresnel;
pub mod height;
pub mod limits;
pub mod medium;
pub mod ndf;
pub mod opaque_core;
pub(crate) mod ordered;
pub(crate) mod parallel;
pub mod params;
pub mod phase;
pub mod rng;
pub mod special;
pub mod surface;
pub mod tracking;

/// Linear RGB, one value per channel.
pub type Rgb = [f64; 3];

pub use error::{Error, ErrorKind, Result};
pub use medium::{FreeFlight, MacrofacetMedium};
pub use params::{medium_from_params, ParamSet, ParamValue};
pub use phase::{MacrofacetPhase, MicroBsdf, PhaseSample, VndfSampling, PHASE_SAMPLE_DIMENSIONS};
