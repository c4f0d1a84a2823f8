//! # macrofacet-validation
//!
//! Development only (not shipped with the library): what the tests of every crate and the
//! validation report share.
//! - [`stats`]: χ² and Kolmogorov–Smirnov tests with their special functions;
//! - [`slab`]: random walks through a semi-infinite macrofacet slab (white furnace, BRDFs);
//! - [`reference`]: independent reference formulas (quadrature, the Heitz et al. 2016 random
//!   walk, Chandrasekhar's H-function, ...) written without the core's code;
//! - [`common`]: test helpers (sphere quadrature, χ² frames, meshes, a planar mean surface).
//!
//! The report: `cargo run --release -p macrofacet-validation --example validate`.

// The conventions of the core crate (`!(x > 0.0)` also rejects NaN), and index loops over
// several parallel arrays, which read better than zipped iterators here.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop, clippy::excessive_precision, clippy::too_many_arguments)]

pub mod common;
pub mod reference;
pub mod slab;
pub mod stats;
