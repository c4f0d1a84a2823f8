//! Certified edge zones: where a thin shell's segment crosses an edge of the mesh, only the edge's
//! two triangles can be closest, so its bound needs those two candidates instead of the grid's
//! (the strip beside an edge is where no face region certifies a piece, [`super::region`]).
//!
//! For an edge shared by triangles `A` and `B`, `S` its middle part (a fraction [`MARGINS`] of its
//! length kept from each end) and `G` the least distance from `S` to every other triangle: a point
//! `q` within `r < G/2` of `S` is within `r` of `A` (which contains `S`) and, through the point
//! of `S` nearest `q`, more than `G − r > r` from every other triangle. So `A` or `B` is strictly
//! the closest at `q`, and a closest-point search over the two finds what the whole mesh's
//! would. The zone, the capsule of radius `r` around `S`, is convex: a segment whose two ends lie
//! in it lies in it.

use super::bvh::Bvh;
use crate::surface::Curvature;
use super::triangle::{closest_on_triangle, segment_parameter, Triangle};
use crate::parallel;
use glam::DVec3;
use std::collections::HashMap;

/// Fractions of an edge's length kept from each of its ends: the triangles around a corner come
/// within about `margin × length` of the middle part, so a larger margin gives a wider zone over
/// a shorter part.
const MARGINS: [f64; LEVELS] = [0.1, 0.25];
const LEVELS: usize = 2;
/// The zones' radii stop at this many edge lengths (a thin shell's crossings need far less, and
/// the competitors searched stay few).
const MAX_RADIUS_EDGES: f64 = 0.125;

/// The zone of one edge of one triangle.
#[derive(Clone, Copy, Debug)]
pub(super) struct EdgeZone {
    /// The other triangle of the edge; `u32::MAX` without a zone (an edge of more or fewer than
    /// two triangles, or of a degenerate one).
    pub neighbour: u32,
    /// The capsule's radius for each margin (0: none).
    radius: [f64; LEVELS],
    /// How the signed distance bends in the zone, where the surface is the two triangles only
    /// and `f` is the signed distance to their dihedral: convex where the neighbour falls away
    /// below this triangle's plane (the solid is locally an intersection of half-spaces),
    /// concave where it rises; `None` for a flat edge, whose side rounding decides.
    pub curvature: Option<Curvature>,
}

impl EdgeZone {
    const NONE: EdgeZone = EdgeZone { neighbour: u32::MAX, radius: [0.0; LEVELS], curvature: None };

    /// The zones of every triangle's edges (edge `k` runs from corner `k` to `k + 1`), in the
    /// triangles' order, on up to `threads` threads. `corners[i]` are triangle `i`'s welded
    /// vertex ids (triangles that share an edge share its two ids); `epsilon` is the rounding
    /// scale of the coordinates.
    pub fn build(bvh: &Bvh, triangles: &[Triangle], corners: &[[u32; 3]], epsilon: f64, threads: usize) -> Vec<[EdgeZone; 3]> {
        let key = |i: usize, k: usize| {
            let (u, v) = (corners[i][k], corners[i][(k + 1) % 3]);
            (u.min(v), u.max(v))
        };
        let mut uses: HashMap<(u32, u32), Vec<(u32, usize)>> = HashMap::new();
        for i in 0..triangles.len() {
            for k in 0..3 {
                uses.entry(key(i, k)).or_default().push((i as u32, k));
            }
        }
        // The edges of exactly two triangles, each once.
        let pairs: Vec<[(u32, usize); 2]> = uses
            .values()
            .filter_map(|sides| match *sides.as_slice() {
                [(i, k), (j, l)] => Some([(i, k), (j, l)]),
                _ => None,
            })
            .collect();
        let zones_of = parallel::map(pairs.len(), threads, Vec::new, |near, n| {
            let [(i, k), (j, _)] = pairs[n];
            let (a, b) = (&triangles[i as usize], &triangles[j as usize]);
            if a.n == DVec3::ZERO || b.n == DVec3::ZERO || corners[i as usize][k] == corners[i as usize][(k + 1) % 3] {
                return None;
            }
            let radius = Self::radii(bvh, triangles, i, k, j, epsilon, near);
            // The neighbour's corner off the edge, against this triangle's plane (the same sign
            // seen from either side of a consistently wound mesh).
            let edge = [a.p[k], a.p[(k + 1) % 3]];
            let off = b.p.iter().copied().find(|c| !edge.contains(c));
            let curvature = off.and_then(|c| {
                let side = a.n.dot(c - a.p[k]);
                let flat = 1e-9 * (c - a.p[k]).length() + 4.0 * epsilon;
                if side < -flat {
                    Some(Curvature::Convex)
                } else if side > flat {
                    Some(Curvature::Concave)
                } else {
                    None
                }
            });
            Some((radius, curvature))
        });
        let mut zones = vec![[EdgeZone::NONE; 3]; triangles.len()];
        for (&[(i, k), (j, l)], zone) in pairs.iter().zip(zones_of) {
            if let Some((radius, curvature)) = zone {
                zones[i as usize][k] = EdgeZone { neighbour: j, radius, curvature };
                zones[j as usize][l] = EdgeZone { neighbour: i, radius, curvature };
            }
        }
        zones
    }

    /// The radius at each margin for edge `k` of triangle `i`, shared with `j`. The other side's
    /// middle part is the same up to the rounding of its ends, which the `4 epsilon` taken off
    /// covers.
    fn radii(bvh: &Bvh, triangles: &[Triangle], i: u32, k: usize, j: u32, epsilon: f64, near: &mut Vec<u32>) -> [f64; LEVELS] {
        let t = &triangles[i as usize];
        let cap = MAX_RADIUS_EDGES * (t.p[(k + 1) % 3] - t.p[k]).length();
        // Every triangle within 2 cap of a middle part lies within this of the edge's midpoint
        // (the parts share it; the first margin's is the longest).
        let (s0, s1) = middle(t, k, 0);
        let complete = bvh.within(triangles, 0.5 * (s0 + s1), 0.5 * (s1 - s0).length() + 2.0 * cap, usize::MAX, near);
        debug_assert!(complete);
        std::array::from_fn(|level| {
            let (s0, s1) = middle(t, k, level);
            let mut gap = 2.0 * cap;
            for &o in near.iter().filter(|&&o| o != i && o != j) {
                let other = &triangles[o as usize];
                // The bounding sphere first: most triangles lie beyond the gap found so far.
                if point_segment_distance(other.centre, s0, s1) - other.radius < gap {
                    gap = gap.min(segment_distance(other, s0, s1));
                }
            }
            (0.5 * gap * (1.0 - 1e-9) - 4.0 * epsilon).max(0.0)
        })
    }

    /// The largest radius over the margins.
    pub fn widest(&self) -> f64 {
        self.radius.iter().copied().fold(0.0, f64::max)
    }

    /// The longest piece `[0, l]`, `l <= length`, of the segment `p + s d` in the zone of edge
    /// `k` of `t`: up to where the ray leaves the capsule ([`capsule_exit`]), moved back by a
    /// relative `1e-12` against rounding, its end checked inside; `None` when `p` lies outside
    /// or the piece is shorter than `min_piece`.
    pub fn piece(&self, t: &Triangle, k: usize, p: DVec3, d: DVec3, length: f64, min_piece: f64) -> Option<f64> {
        // The capsule lies within its radius of the triangle's plane (most points of a thick
        // shell fail here, at once).
        if t.n.dot(p - t.p[k]).abs() > self.widest() {
            return None;
        }
        let mut best: Option<f64> = None;
        // (The wider margin first: its shorter middle part stays farther from the corners'
        // triangles, so its capsule is as wide or wider and more often holds the whole segment;
        // the thin torus anchor ran 0.2 % fewer instructions.)
        for level in (0..LEVELS).rev() {
            let r = self.radius[level];
            let (s0, s1) = middle(t, k, level);
            let inside = |s: f64| point_segment_distance(p + s * d, s0, s1) <= r;
            if !(r > 0.0 && inside(0.0)) {
                continue;
            }
            let piece = (capsule_exit(p, d, s0, s1, r) * (1.0 - 1e-12)).min(length);
            if !(piece >= min_piece && inside(piece)) {
                continue;
            }
            if piece == length {
                return Some(length);
            }
            best = Some(best.map_or(piece, |b: f64| b.max(piece)));
        }
        best
    }
}

/// Where the ray `p + s d`, `s >= 0`, leaves the capsule of radius `r` around the segment
/// `s0 s1`, for `p` inside it. The capsule is convex, the union of its cylinder (within the
/// segment's span) and its two end balls, each convex too: the ray's interval in it is the union
/// of its intervals in them, and ends where the last of those does.
fn capsule_exit(p: DVec3, d: DVec3, s0: DVec3, s1: DVec3, r: f64) -> f64 {
    // The real roots of |q + s v|² = r², in order (none: an empty interval).
    let roots = |q: DVec3, v: DVec3| -> (f64, f64) {
        let (a, b, c) = (v.length_squared(), q.dot(v), q.length_squared() - r * r);
        if a > 0.0 {
            let disc = b * b - a * c;
            if disc >= 0.0 {
                let root = disc.sqrt();
                return ((-b - root) / a, (-b + root) / a);
            }
        } else if c <= 0.0 {
            return (f64::NEG_INFINITY, f64::INFINITY);
        }
        (f64::INFINITY, f64::NEG_INFINITY)
    };
    let mut end = [s0, s1].iter().map(|&centre| roots(p - centre, d).1).fold(f64::NEG_INFINITY, f64::max);
    let axis = s1 - s0;
    let span = axis.length();
    if span > 0.0 {
        let u = axis / span;
        let (along, rate) = ((p - s0).dot(u), d.dot(u));
        // Within the span: 0 <= along + s rate <= span.
        let (lo, hi) = if rate != 0.0 {
            let (a, b) = (-along / rate, (span - along) / rate);
            (a.min(b), a.max(b))
        } else if (0.0..=span).contains(&along) {
            (f64::NEG_INFINITY, f64::INFINITY)
        } else {
            (f64::INFINITY, f64::NEG_INFINITY)
        };
        // Within the radius of the axis: the components across it.
        let (across_lo, across_hi) = roots((p - s0) - along * u, d - rate * u);
        if lo.max(across_lo) <= hi.min(across_hi) {
            end = end.max(hi.min(across_hi));
        }
    }
    end.max(0.0)
}

/// The middle part of edge `k` of `t` at margin `level`.
fn middle(t: &Triangle, k: usize, level: usize) -> (DVec3, DVec3) {
    let (a, b) = (t.p[k], t.p[(k + 1) % 3]);
    let m = MARGINS[level];
    (a + m * (b - a), a + (1.0 - m) * (b - a))
}

fn point_segment_distance(p: DVec3, s0: DVec3, s1: DVec3) -> f64 {
    (p - (s0 + segment_parameter(p, s0, s1) * (s1 - s0))).length()
}

/// The distance between the segments `p1 q1` and `p2 q2` (Ericson, *Real-Time Collision
/// Detection*, 5.1.9): that of the closest pair, clamped to both segments.
fn segment_segment_distance(p1: DVec3, q1: DVec3, p2: DVec3, q2: DVec3) -> f64 {
    let (d1, d2, r) = (q1 - p1, q2 - p2, p1 - p2);
    let (a, e, f) = (d1.length_squared(), d2.length_squared(), d2.dot(r));
    let (s, t) = if a == 0.0 && e == 0.0 {
        (0.0, 0.0)
    } else if a == 0.0 {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(r);
        if e == 0.0 {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            // Parallel segments: any s, here 0, with its best t.
            let s = if denom > 0.0 { ((b * f - c * e) / denom).clamp(0.0, 1.0) } else { 0.0 };
            let t = (b * s + f) / e;
            if t < 0.0 {
                ((-c / a).clamp(0.0, 1.0), 0.0)
            } else if t > 1.0 {
                (((b - c) / a).clamp(0.0, 1.0), 1.0)
            } else {
                (s, t)
            }
        }
    };
    ((p1 + s * d1) - (p2 + t * d2)).length()
}

/// The distance between the segment `s0 s1` and triangle `t`. Where they do not meet, the closest
/// pair has an end of the segment or a point of the triangle's boundary; where the segment crosses
/// the triangle's plane, the crossing's own distance covers a segment through its inside (0 up to
/// rounding, which the callers' margins cover).
pub(super) fn segment_distance(t: &Triangle, s0: DVec3, s1: DVec3) -> f64 {
    let ends = [s0, s1].map(|s| closest_on_triangle(t, s, 0).distance_sq.sqrt());
    let edges = (0..3).map(|k| segment_segment_distance(s0, s1, t.p[k], t.p[(k + 1) % 3]));
    let mut distance = edges.fold(ends[0].min(ends[1]), f64::min);
    let (h0, h1) = (t.n.dot(s0 - t.p[0]), t.n.dot(s1 - t.p[0]));
    if t.n != DVec3::ZERO && h0 * h1 <= 0.0 && h0 != h1 {
        let crossing = s0 + (h0 / (h0 - h1)) * (s1 - s0);
        distance = distance.min(closest_on_triangle(t, crossing, 0).distance_sq.sqrt());
    }
    distance
}

#[cfg(test)]
mod tests {
    use super::super::triangle::from_corners;
    use super::*;
    use crate::rng::Pcg32;

    /// A ray from inside a capsule leaves it where the closed form says: just before, inside;
    /// just after, outside (random capsules, some degenerate to a ball, and rays of any length).
    #[test]
    fn capsule_exit_is_where_the_ray_leaves() {
        let mut rng = Pcg32::new(5, 9);
        let mut point = |scale: f64| DVec3::new(rng.next_f64() - 0.5, rng.next_f64() - 0.5, rng.next_f64() - 0.5) * scale;
        let mut checked = 0;
        for k in 0..20_000 {
            let s0 = point(2.0);
            let s1 = if k % 10 == 0 { s0 } else { s0 + point(2.0) };
            let r = 0.05 + 0.5 * (point(1.0).x + 0.5);
            let p = s0 + (s1 - s0) * (point(1.0).x + 0.5) + point(2.0 * r);
            if point_segment_distance(p, s0, s1) > r {
                continue;
            }
            let d = point(1.0).normalize() * if k % 3 == 0 { 1.0 } else { 3.0 };
            let end = capsule_exit(p, d, s0, s1, r);
            let tol = 1e-9 * (1.0 + end * d.length());
            assert!(point_segment_distance(p + end * d, s0, s1) <= r + tol, "case {k}: the exit {end} lies outside");
            assert!(point_segment_distance(p + (end + 1e-6) * d, s0, s1) > r - tol, "case {k}: the ray is still inside past the exit {end}");
            checked += 1;
        }
        assert!(checked > 5000, "{checked} rays checked");
    }

    /// The segment–triangle distance is the least over dense samples of the segment (which can
    /// only be larger, by at most half a sample step), and never above it.
    #[test]
    fn segment_distance_matches_sampling() {
        let mut rng = Pcg32::new(11, 4);
        let mut point = |scale: f64| DVec3::new(rng.next_f64() - 0.5, rng.next_f64() - 0.5, rng.next_f64() - 0.5) * scale;
        for k in 0..3000 {
            let mut t = from_corners([point(2.0), point(2.0), point(2.0)]);
            if k % 10 == 0 {
                t = from_corners([t.p[0], t.p[1], t.p[0] + 0.5 * (t.p[1] - t.p[0])]); // degenerate
            }
            let (s0, s1) = (point(3.0), point(3.0));
            let exact = segment_distance(&t, s0, s1);
            let steps = 4000;
            let sampled = (0..=steps).map(|i| closest_on_triangle(&t, s0 + (i as f64 / steps as f64) * (s1 - s0), 0).distance_sq.sqrt()).fold(f64::INFINITY, f64::min);
            let half_step = 0.5 * (s1 - s0).length() / steps as f64;
            assert!(exact <= sampled + 1e-12, "case {k}: {exact} above the sampled {sampled}");
            assert!(exact >= sampled - half_step - 1e-12, "case {k}: {exact} below the sampled {sampled} by more than half a step");
        }
    }
}
