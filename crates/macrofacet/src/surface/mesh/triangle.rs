//! One triangle of a mesh surface and its closest point to a query point (Ericson, *Real-Time
//! Collision Detection*, 5.1.5), with the feature (face, edge, corner) the point lies on, which
//! decides the pseudo-normal that signs the distance (Bærentzen & Aanæs 2005).

use glam::{DVec2, DVec3};

/// Where on a triangle the closest point lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Feature {
    Face,
    /// Edge `i` runs from corner `i` to corner `(i + 1) % 3`.
    Edge(usize),
    Vertex(usize),
}

/// The geometry of one triangle: all that closest-point searches read, kept compact (128 bytes)
/// so that a search touches few cache lines; the rest is in [`Attributes`].
#[derive(Clone, Debug)]
pub(super) struct Triangle {
    pub p: [DVec3; 3],
    /// Unit face normal from the winding; zero for a degenerate (zero-area) triangle.
    pub n: DVec3,
    /// A bounding sphere (centre, radius): a cheap lower bound of the distance.
    pub centre: DVec3,
    pub radius: f64,
}

impl Triangle {
    /// Corners `p` and unit normal `n` (zero for a degenerate triangle), with the bounding sphere
    /// about the centroid.
    pub fn new(p: [DVec3; 3], n: DVec3) -> Triangle {
        let centre = (p[0] + p[1] + p[2]) / 3.0;
        Triangle { p, n, centre, radius: p.iter().map(|v| (*v - centre).length()).fold(0.0, f64::max) }
    }
}

/// What a triangle's surface points need beyond its geometry: the sign, the frame and the uv.
#[derive(Clone, Debug)]
pub(super) struct Attributes {
    /// Pseudo-normals of the edges (sum of the adjacent faces' normals) and of the corners
    /// (angle-weighted), for the sign of the distance.
    pub edge_pn: [DVec3; 3],
    pub vertex_pn: [DVec3; 3],
    /// Vertex (shading) normals, when the mesh has them.
    pub shading: Option<[DVec3; 3]>,
    /// A lower bound of `|Σ b_i n_i|` over the triangle's barycentric coordinates (0: none).
    pub shading_min_length: f64,
    /// A Lipschitz constant of `c ↦ Σ b_i(c) n_i` over the triangle (per unit of distance).
    pub shading_lipschitz: f64,
    /// Mitsuba's `dp/du` for this triangle.
    pub dpdu: DVec3,
    /// Texture coordinates of the corners, when the mesh has them.
    pub uv: Option<[DVec2; 3]>,
}

/// The closest point of a triangle to a query point.
#[derive(Clone, Copy, Debug)]
pub(super) struct Closest {
    pub triangle: u32,
    pub point: DVec3,
    pub barycentric: DVec3,
    pub feature: Feature,
    pub distance_sq: f64,
}

impl Closest {
    /// The starting value of a search: nothing found yet.
    pub const NONE: Closest = Closest { triangle: u32::MAX, point: DVec3::ZERO, barycentric: DVec3::ZERO, feature: Feature::Face, distance_sq: f64::INFINITY };
}

/// The order of closest points: by distance, ties (points on a medial surface) to the smaller
/// triangle index, so that every search returns the same triangle, hence the same frame.
pub(super) fn closer(a: &Closest, b: &Closest) -> bool {
    a.distance_sq < b.distance_sq || (a.distance_sq == b.distance_sq && a.triangle < b.triangle)
}

/// The closest point among `candidates`, by [`closer`], starting from `best` (e.g.
/// [`Closest::NONE`]). A triangle whose bounding sphere is farther than the best so far is
/// skipped (`>`: an equally distant one may still win the tie).
pub(super) fn closest_among(triangles: &[Triangle], p: DVec3, candidates: &[u32], mut best: Closest) -> Closest {
    for &i in candidates {
        let t = &triangles[i as usize];
        // (Nothing found yet, nothing is skipped: the test would pass.)
        if best.distance_sq != f64::INFINITY && !may_be_within(t, p, best.distance_sq) {
            continue;
        }
        let c = closest_on_triangle(t, p, i);
        if closer(&c, &best) {
            best = c;
        }
    }
    best
}

/// False when `t` is certainly farther than `sqrt(distance_sq)` from `p`: the triangle lies in
/// its plane within `radius` of its centre, so its distance is at least that to the disc, whose
/// square is the plane's distance squared plus the in-plane gap squared (tighter than the plane
/// or the bounding sphere alone where `p` lies deep below many triangles: the volume-like torus
/// of the default scene computed 53 % fewer closest points). Each part is lowered by its
/// rounding, a few ulps of the coordinates (and the limit raised by 1e-12 relative, as the
/// distances themselves are rounded).
pub(super) fn may_be_within(t: &Triangle, p: DVec3, distance_sq: f64) -> bool {
    let limit = distance_sq * (1.0 + 1e-12);
    let slack = 1e-14 * (p.abs().max_element() + t.centre.abs().max_element() + t.radius);
    let v = p - t.centre;
    let height = t.n.dot(v);
    let plane = (height.abs() - slack).max(0.0);
    if plane * plane > limit {
        return false;
    }
    let gap = ((v - height * t.n).length() - t.radius - slack).max(0.0);
    !(plane * plane + gap * gap > limit)
}

/// The parameter `s ∈ [0, 1]` of the point `a + s (b − a)` of a segment closest to `p` (0 for a
/// segment of zero length).
pub(super) fn segment_parameter(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let e = b - a;
    if e.length_squared() > 0.0 {
        ((p - a).dot(e) / e.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// The closest point of triangle `t` (index `index`) to `p`. A degenerate triangle is treated
/// as its three edges.
pub(super) fn closest_on_triangle(t: &Triangle, p: DVec3, index: u32) -> Closest {
    let [a, b, c] = t.p;
    let make = |point: DVec3, bary: DVec3, feature: Feature| Closest { triangle: index, point, barycentric: bary, feature, distance_sq: (p - point).length_squared() };
    // A zero-area triangle is its three edges.
    let on_edges = || {
        (0..3)
            .map(|i| {
                let (u, v) = (t.p[i], t.p[(i + 1) % 3]);
                let s = segment_parameter(p, u, v);
                let mut bary = DVec3::ZERO;
                bary[i] = 1.0 - s;
                bary[(i + 1) % 3] = s;
                make(u + s * (v - u), bary, Feature::Edge(i))
            })
            .min_by(|x, y| x.distance_sq.total_cmp(&y.distance_sq))
            .expect("three edges")
    };
    if t.n == DVec3::ZERO {
        return on_edges();
    }
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return make(a, DVec3::X, Feature::Vertex(0));
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return make(b, DVec3::Y, Feature::Vertex(1));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return make(a + v * ab, DVec3::new(1.0 - v, v, 0.0), Feature::Edge(0));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return make(c, DVec3::Z, Feature::Vertex(2));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return make(a + w * ac, DVec3::new(1.0 - w, 0.0, w), Feature::Edge(2));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return make(b + w * (c - b), DVec3::new(0.0, 1.0 - w, w), Feature::Edge(1));
    }
    // A sliver whose area rounds to zero here (its normal did not) is its edges too (found by
    // fuzzing: 5e-37 wide and 40 long, every distance NaN).
    let sum = va + vb + vc;
    if !(sum > 0.0) {
        return on_edges();
    }
    let denom = 1.0 / sum;
    let (v, w) = (vb * denom, vc * denom);
    make(a + ab * v + ac * w, DVec3::new(1.0 - v - w, v, w), Feature::Face)
}

/// A triangle with its normal from the winding (zero for a degenerate one), for tests.
#[cfg(test)]
pub(super) fn from_corners(p: [DVec3; 3]) -> Triangle {
    Triangle::new(p, (p[1] - p[0]).cross(p[2] - p[0]).try_normalize().unwrap_or(DVec3::ZERO))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;

    #[test]
    fn pruning_never_drops_a_triangle_at_the_search_distance() {
        // A search keeps every triangle as close as the best so far (ties decide by index), so
        // the cheap test must pass whenever the distance equals the limit: far and near points,
        // points on the triangle's plane, slivers, and coordinates offset far from the origin.
        let mut rng = Pcg32::new(7, 9);
        let mut uniform = |scale: f64| DVec3::new(rng.next_f64() - 0.5, rng.next_f64() - 0.5, rng.next_f64() - 0.5) * scale;
        for k in 0..200_000 {
            let origin = [DVec3::ZERO, DVec3::splat(1e3), DVec3::new(-7e5, 3e5, 1.0)][k % 3];
            let size = [1.0, 1e-6, 1e4][k / 3 % 3];
            let mut corners = [origin + uniform(size), origin + uniform(size), origin + uniform(size)];
            if k % 7 == 0 {
                corners[2] = corners[0] + 1e-9 * (corners[1] - corners[0]); // a sliver
            }
            let t = from_corners(corners);
            let mut p = origin + uniform(size * [1e-9, 1e-3, 1.0, 10.0][k / 9 % 4]);
            if k % 5 == 0 && t.n != DVec3::ZERO {
                p -= t.n.dot(p - t.p[0]) * t.n; // on the plane, up to rounding
            }
            let c = closest_on_triangle(&t, p, 0);
            assert!(may_be_within(&t, p, c.distance_sq), "triangle {corners:?} at {} from {p} pruned at its own distance", c.distance_sq.sqrt());
        }
    }
}
