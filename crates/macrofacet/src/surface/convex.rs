//! Segment bounds of convex (or concave) signed-distance functions from their two ends.
//!
//! Along a line, a convex `f` lies above its tangent at the start and below the chord, and its
//! derivative `f' = d·∇f` increases; so with the frame normal `n = ∇f` the two end points bound
//! everything the tracker needs. Spheres, boxes and every convex solid have convex signed
//! distances (outside: the distance to a convex set; inside: a maximum of plane distances); with
//! flipped normals they are concave.

use super::{SegmentBound, SegmentEnd, SurfacePoint};
use glam::DVec3;

/// The sign of the second derivative of `f` along every line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Curvature {
    /// `f'' >= 0`: e.g. a sphere or box with outward normals.
    Convex,
    /// `f'' <= 0`: the same with flipped normals.
    Concave,
}

/// The bound of the segment `p + s d`, `s ∈ [0, length]`, from `start = point(p)` and
/// `end = point(p + length d)`, where the frame normal is `∇f`.
pub fn convex_bound(start: &SurfacePoint, end: &SurfacePoint, d: DVec3, length: f64, curvature: Curvature) -> SegmentBound {
    let (c0, c1) = (d.dot(start.normal), d.dot(end.normal));
    let tangent = [start.f, start.f + c0 * length];
    let chord = [start.f, end.f];
    let (f_lo, f_hi, cos) = match curvature {
        Curvature::Convex => (tangent, chord, [c0, c1]),
        Curvature::Concave => (chord, tangent, [c1, c0]),
    };
    // Rounding can leave the derivative range a hair out of order for a straight segment, and a
    // host's normal (within 1e-4 of unit length) a hair outside [-1, 1]: clamped, then ordered.
    let cos = cos.map(|c| c.clamp(-1.0, 1.0));
    let cos = [cos[0].min(cos[1]), cos[0].max(cos[1])];
    SegmentBound { length, f_lo, f_hi, cos, end: SegmentEnd::Point(*end) }
}
