//! Minima and maxima of values known not to be NaN (a validated point's coordinates, distances
//! and bounds): one comparison, where `f64::min` and `f64::max` also handle NaN operands
//! (IEEE `minNum`), ~4 instructions more each. On the hot paths of tracking through a mesh they
//! were a few percent of the instructions (docs/performance.md, session 30). Where an operand
//! may be NaN, keep `f64::min`/`f64::max`, which return the other operand; `less` and `more`
//! return their first operand whenever either is NaN.

/// The smaller of `a` and `b`, neither NaN.
#[inline]
pub(crate) fn less(a: f64, b: f64) -> f64 {
    if b < a {
        b
    } else {
        a
    }
}

/// The larger of `a` and `b`, neither NaN.
#[inline]
pub(crate) fn more(a: f64, b: f64) -> f64 {
    if b > a {
        b
    } else {
        a
    }
}

/// The largest of `|v.x|`, `|v.y|`, `|v.z|` for a vector without NaN (glam's `max_element` of
/// `abs` by comparisons).
#[inline]
pub(crate) fn largest_magnitude(v: glam::DVec3) -> f64 {
    let a = v.abs();
    more(more(a.x, a.y), a.z)
}
