//! Certified face regions: where one triangle is provably the closest, so that the signed
//! distance is exactly the distance to its plane and a thin shell's segment bound costs O(1).
//!
//! For triangle `T` (unit normal `n`) and a side `s = ±1`, a point `p = x + t s n` with its foot
//! `x` in `T` and `t >= 0` is at distance `t` from `T`. It is at least as far from another
//! triangle `T'` whenever some unit `u` gives `dist(p, T') >= u·p − max_{y∈T'} u·y >= t`, i.e.
//!
//! `t (1 − s u·n) <= u·x − max_{y∈T'} u·y`,
//!
//! a condition affine in `x` (and linear in `t`). With `u = s n` it holds for all `t` when `T'`
//! lies wholly on the other side of `T`'s plane (the convex side of a surface needs nothing
//! else); with `u = ±n'` (the plane of `T'`) it gives `t <= e cot(θ/2)` at distance `e` from a
//! concave edge of dihedral angle `θ`. Over the *inset* `{x : e_i(x) >= m}` (`e_i` the distance
//! to edge `i`'s line, `m` a margin), the affine right-hand side is smallest at the inset's
//! corners, so each margin gets a certified height `H_s(m)`. Only triangles within `2 H_max` of
//! `T` can compete below `H_max`.
//!
//! The region `{e_i >= m, 0 <= t <= H_s(m)}` is convex, and so is its union with the mirrored
//! one across the face: a segment whose two ends lie in it lies in it, and there `f = n·p − n·p0`
//! exactly and the frame normal is `T`'s (interpolated) normal.

use super::bvh::Bvh;
use super::triangle::{Closest, Feature, Triangle};
use crate::frame::rescaled;
use crate::ordered::{less, more};
use crate::parallel;
use glam::DVec3;

/// Margins from the edges, as fractions of the inradius: a larger margin keeps segments away
/// from the edges (where concave neighbours compete) and certifies higher.
const MARGINS: [f64; LEVELS] = [0.0, 1.0 / 128.0, 1.0 / 32.0, 1.0 / 8.0, 0.25, 0.5];
const LEVELS: usize = 6;
/// The certified heights stop at this many longest edges of the triangle (a shell that thick
/// spans many triangles and takes the general bound anyway), and at the mesh's covered distance
/// (its reach, [`super::TriangleMesh::new`]).
const HEIGHT_EDGES: f64 = 0.5;
/// The uncertified strip beside an edge is taken as this many of the first margins of the
/// triangle being left wide (its own, and its neighbour's of up to three times the inradius).
const STRIP_MARGINS: f64 = 4.0;

/// One triangle's certified regions on both sides of its face.
#[derive(Clone, Copy, Debug)]
pub(super) struct FaceRegion {
    /// `e_i(p) = inward[i]·p + offset[i]`: the distance from `p`'s projection on the plane to
    /// the line of edge `i` (corner `i` to `i + 1`), positive inside.
    inward: [DVec3; 3],
    offset: [f64; 3],
    /// `1 / h_i`, `h_i` the altitude from edge `i` to the opposite corner `i + 2`: that corner's
    /// barycentric coordinate is `e_i / h_i`.
    inverse_altitude: [f64; 3],
    /// `t(p) = n·p − plane`.
    plane: f64,
    margin: [f64; LEVELS],
    /// Certified heights above (`[0]`) and below (`[1]`) the face for each margin; 0 where
    /// nothing is certified (degenerate triangles).
    height: [[f64; LEVELS]; 2],
}

/// A certified piece of a segment: `f` is the plane distance of its triangle along it.
#[derive(Clone, Copy, Debug)]
pub(super) struct Piece {
    pub length: f64,
}

impl FaceRegion {
    /// Certifies nothing (no point is that far inside).
    const NONE: FaceRegion = FaceRegion { inward: [DVec3::ZERO; 3], offset: [0.0; 3], inverse_altitude: [0.0; 3], plane: 0.0, margin: [f64::INFINITY; LEVELS], height: [[0.0; LEVELS]; 2] };

    /// The certified regions of every triangle (in the hierarchy's order), with heights up to
    /// `covered` at most, on up to `threads` threads; `epsilon` is the rounding scale of the
    /// coordinates, taken off every certified height.
    pub fn build(bvh: &Bvh, triangles: &[Triangle], epsilon: f64, covered: f64, threads: usize) -> Vec<FaceRegion> {
        // Every triangle's cones at its corners, once (each serves all the neighbours there).
        let cones: Vec<[Option<Cone>; 3]> = triangles.iter().map(|t| t.p.map(|v| Cone::at(t, v))).collect();
        parallel::map(triangles.len(), threads, || (Vec::new(), Vec::new()), |(near, by_gap), i| Self::of(bvh, triangles, &cones, i, epsilon, covered, near, by_gap))
    }

    /// `near` and `by_gap`: scratch space, reused from triangle to triangle.
    #[allow(clippy::too_many_arguments)]
    fn of(bvh: &Bvh, triangles: &[Triangle], cones: &[[Option<Cone>; 3]], i: usize, epsilon: f64, covered: f64, near: &mut Vec<u32>, by_gap: &mut Vec<(f64, u32)>) -> FaceRegion {
        let t = &triangles[i];
        let n = t.n;
        if n == DVec3::ZERO {
            return FaceRegion::NONE;
        }
        let edge = |k: usize| t.p[(k + 1) % 3] - t.p[k];
        let lengths = [0, 1, 2].map(|k| edge(k).length());
        let perimeter: f64 = lengths.iter().sum();
        let twice_area = edge(0).cross(t.p[2] - t.p[0]).length();
        let inradius = twice_area / perimeter;
        if !(inradius > 0.0) {
            return FaceRegion::NONE;
        }
        // Rescaled before normalising, as the face normal (a tiny mesh's are subnormal).
        let inward = [0, 1, 2].map(|k| rescaled(n.cross(edge(k))).normalize());
        let offset = [0, 1, 2].map(|k| -inward[k].dot(t.p[k]));
        // The incentre: the inset at margin `f r` (`r` the inradius) is the triangle scaled by
        // `1 − f` about it.
        let incentre = (lengths[1] * t.p[0] + lengths[2] * t.p[1] + lengths[0] * t.p[2]) / perimeter;
        let margin = MARGINS.map(|f| f * inradius);
        let h_max = (HEIGHT_EDGES * lengths.iter().copied().fold(0.0, f64::max)).min(covered);
        // How far each inset's corner `k` lies from `T`'s: `f |p_k − incentre|`.
        let from_incentre = t.p.map(|c| (c - incentre).length());

        let mut height = [[h_max; LEVELS]; 2];
        // Competitors within 2 h_max of T: within 2 h_max + T's radius of its centre; nearest
        // first, since a triangle at distance D from T constrains only heights above D/2.
        let complete = bvh.within(triangles, t.centre, 2.0 * h_max + t.radius, usize::MAX, near);
        debug_assert!(complete);
        let gap = |j: u32| {
            let o = &triangles[j as usize];
            (t.centre - o.centre).length() - t.radius - o.radius
        };
        // (Each gap computed once, not at every comparison; the sort is stable, as before.)
        by_gap.clear();
        by_gap.extend(near.iter().map(|&j| (gap(j), j)));
        by_gap.sort_by(|a, b| a.0.total_cmp(&b.0));
        for &(gap_j, j) in by_gap.iter() {
            if j as usize == i {
                continue;
            }
            // A triangle at distance D from T is farther than any point of T's prism up to D/2
            // above or below it: heights up to half the gap need no test against it.
            let half_gap = 0.5 * gap_j;
            let highest = height.iter().flatten().copied().fold(0.0, more);
            if half_gap > highest {
                break;
            }
            let other = &triangles[j as usize];
            // A neighbour sharing one corner: the bound of the cones at that corner (the angle
            // between them for both sides, once).
            let mut shared = (0..3).filter(|&k| other.p.contains(&t.p[k]));
            let corner = match (shared.next(), shared.next()) {
                (Some(k), None) => Some(k),
                _ => None,
            };
            let their_cone_at = |k: usize| other.p.iter().position(|q| *q == t.p[k]).and_then(|m| cones[j as usize][m]);
            let mut cones_gap = None;
            // Directions u, each a valid lower bound: the plane of T (wholly on the far side:
            // no constraint), the plane of T' either way, and the direction between centroids.
            // Their dot products once for both sides (an opposite direction's are the negated
            // ones, exactly); per side only `k = 1 − u·sn` changes.
            let own = Along::new(n, t, incentre, other);
            let theirs = (other.n != DVec3::ZERO).then(|| Along::new(other.n, t, incentre, other));
            let between = (t.centre - other.centre).normalize_or_zero();
            let centres = (between != DVec3::ZERO).then(|| Along::new(between, t, incentre, other));
            let (own_k, their_cos, between_cos) = (1.0 - n.dot(n), other.n.dot(n), between.dot(n));
            for (side, s) in [(0, 1.0), (1, -1.0)] {
                let plane = own.bound(s, own_k);
                let others = [theirs.map(|a| a.bound(1.0, 1.0 - s * their_cos)), theirs.map(|a| a.bound(-1.0, 1.0 + s * their_cos)), centres.map(|a| a.bound(1.0, 1.0 - s * between_cos))];
                let mut per_distance = None;
                for level in 0..LEVELS {
                    if height[side][level] <= half_gap {
                        continue;
                    }
                    let f = MARGINS[level];
                    let by_plane = plane.certified_height(f, epsilon);
                    if by_plane == f64::INFINITY {
                        continue; // (the most any bound certifies)
                    }
                    let by_cone = match corner {
                        Some(k) => {
                            let factor = *per_distance.get_or_insert_with(|| {
                                let (my_cone, their_cone) = (cones[i][k]?, their_cone_at(k)?);
                                corner_cone(*cones_gap.get_or_insert_with(|| my_cone.gap(&their_cone)), &their_cone, s * n)
                            });
                            // (∞: the neighbour's cone lies beyond T's plane, at every margin.)
                            factor.map_or(0.0, |c| if c == f64::INFINITY { c } else { c * (f * from_incentre[k]) })
                        }
                        None => 0.0,
                    };
                    let best = others.iter().flatten().map(|b| b.certified_height(f, epsilon)).fold(more(by_cone, by_plane), more);
                    height[side][level] = less(height[side][level], best);
                }
            }
        }
        // Rounding of the queries' coordinates: certify a little less.
        let height = height.map(|hs| hs.map(|h| (h * (1.0 - 1e-9) - 4.0 * epsilon).max(0.0)));
        let inverse_altitude = lengths.map(|l| l / twice_area);
        FaceRegion { inward, offset, inverse_altitude, plane: n.dot(t.p[0]), margin, height }
    }

    /// The closest point of triangle `index` (unit normal `n`, this region's) to `p`, where the
    /// region certifies `p` ([`Self::piece`]'s points; else see [`Self::certified_closest`]):
    /// `p`'s projection on the face, in O(1) (the general test, [`super::triangle::
    /// closest_on_triangle`], first decides which feature is closest).
    pub fn face_closest(&self, n: DVec3, p: DVec3, index: u32) -> Closest {
        self.projection(n, p, self.edge_distances(p), n.dot(p) - self.plane, index)
    }

    /// [`Self::face_closest`] where the region certifies `p`, else `None`.
    pub fn certified_closest(&self, n: DVec3, p: DVec3, index: u32) -> Option<Closest> {
        let (e, t) = (self.edge_distances(p), n.dot(p) - self.plane);
        self.certifies(e, t).then(|| self.projection(n, p, e, t, index))
    }

    /// `e_i(p)` for the three edges.
    pub fn edge_distances(&self, p: DVec3) -> [f64; 3] {
        [0, 1, 2].map(|k| self.edge_distance(k, p))
    }

    /// `e_k(p)`, the distance from `p`'s projection on the plane to the line of edge `k`
    /// (positive inside): `|e_k(p)|` is at most `p`'s distance to that line.
    pub fn edge_distance(&self, k: usize, p: DVec3) -> f64 {
        self.inward[k].dot(p) + self.offset[k]
    }

    /// Whether the point with edge distances `e` at height `t` is certified (its heights grow
    /// with the margin: the largest margin below its least `e_i` decides).
    fn certifies(&self, e: [f64; 3], t: f64) -> bool {
        let e_min = less(less(e[0], e[1]), e[2]);
        match (0..LEVELS).rev().find(|&level| e_min >= self.margin[level]) {
            Some(level) => if t >= 0.0 { t <= self.height[0][level] } else { -t <= self.height[1][level] },
            None => false,
        }
    }

    /// The projection of `p` (edge distances `e`, height `t`) on the face. Corner `i + 2` lies
    /// opposite edge `i`; the coordinates sum to 1 as [`super::triangle::closest_on_triangle`]'s.
    /// (In a certified region every `e_i >= 0` up to rounding: the projection is the closest
    /// point of the triangle, at distance `|t|`.)
    fn projection(&self, n: DVec3, p: DVec3, e: [f64; 3], t: f64, index: u32) -> Closest {
        let (v, w) = (e[2] * self.inverse_altitude[2], e[0] * self.inverse_altitude[0]);
        Closest { triangle: index, point: p - t * n, barycentric: DVec3::new(1.0 - v - w, v, w), feature: Feature::Face, distance_sq: t * t }
    }

    /// Where a segment from `p` on the boundary of the region's first inset (margin
    /// `margin[1]`, the smallest that certifies any height), heading out across an edge, is past
    /// the strip along that edge that no triangle certifies (the margins of this triangle and of
    /// its neighbour, taken as up to [`STRIP_MARGINS`] of this one's): the length over which only
    /// the general bound applies. `None` when `p` is not on that boundary heading out.
    pub fn strip_crossing(&self, p: DVec3, d: DVec3) -> Option<f64> {
        let m = self.margin[1];
        (0..3)
            .filter_map(|k| {
                let (e, de) = (self.inward[k].dot(p) + self.offset[k], self.inward[k].dot(d));
                (de < 0.0 && e >= 0.5 * m && e <= m * (1.0 + 1e-9) + 1e-12 * self.plane.abs()).then(|| (e + STRIP_MARGINS * m) / -de)
            })
            .reduce(f64::max)
    }

    /// The longest certified piece of the segment `p + s d`, `s ∈ [0, length]`, of triangle `t`
    /// (whose region this is); `None` when `p` is not certified.
    pub fn piece(&self, n: DVec3, p: DVec3, d: DVec3, length: f64) -> Option<Piece> {
        let e0 = self.edge_distances(p);
        let de = [0, 1, 2].map(|k| self.inward[k].dot(d));
        let (t0, dt) = (n.dot(p) - self.plane, n.dot(d));
        let e_min = less(less(e0[0], e0[1]), e0[2]);
        let mut best: Option<f64> = None;
        for level in (0..LEVELS).rev() {
            let m = self.margin[level];
            let [above, below] = [self.height[0][level], self.height[1][level]];
            if e_min < m || !(t0 <= above && -t0 <= below) || (above == 0.0 && below == 0.0) {
                continue;
            }
            let mut reach = length;
            for k in 0..3 {
                if de[k] < 0.0 {
                    reach = less(reach, (e0[k] - m) / -de[k]);
                }
            }
            // The height moves linearly from t0 toward one side's limit.
            if dt > 0.0 {
                reach = less(reach, (above - t0) / dt);
            } else if dt < 0.0 {
                reach = less(reach, (below + t0) / -dt);
            }
            // (No level reaches beyond the segment.)
            if reach >= length {
                return Some(Piece { length });
            }
            if reach > best.unwrap_or(0.0) {
                best = Some(reach);
            }
        }
        best.map(|length| Piece { length })
    }
}

/// For a neighbour `other` that shares only corner `k` of `t`: a factor `c` such that every point
/// `x + τ sn` with `x` in `t` at distance `r` from the corner `v` and `τ <= c r` is at least `τ`
/// from `other`; `None` when the cones at `v` touch, `∞` when `other` lies wholly on the far side.
/// `gap` is `1 − cos γ` ([`Cone::gap`]), `theirs` `other`'s cone at `v`.
///
/// With `z = y − v` for `y` in `other` and `h = sn·z > 0`, `|x + τ sn − y| >= τ` iff
/// `τ <= |r − z|² / (2h)`, and over `|z|` that is at least `|r| (1 − r̂·ẑ)/h >= r (1 − cos γ)/h_max`:
/// `γ` the least angle between the two triangles' cones at `v`, `h_max` the most `sn·ẑ` over
/// `other`'s cone.
fn corner_cone(gap: Option<f64>, theirs: &Cone, sn: DVec3) -> Option<f64> {
    let h_max = theirs.most(sn) + 1e-12;
    if h_max <= 0.0 {
        return Some(f64::INFINITY);
    }
    gap.map(|gap| gap / h_max)
}

/// A triangle's cone at its corner `v`: the unit directions of its two edges from `v`.
#[derive(Clone, Copy, Debug)]
struct Cone {
    ends: [DVec3; 2],
    /// `ends[0] × ends[1]`, and it normalised (`None` for a degenerate cone).
    cross: DVec3,
    normal: Option<DVec3>,
}

impl Cone {
    /// `None` unless exactly two corners differ from `v` (a degenerate triangle's).
    fn at(t: &Triangle, v: DVec3) -> Option<Cone> {
        let mut rest = t.p.iter().filter(|q| **q != v).map(|q| (*q - v).normalize_or_zero());
        let ends = match (rest.next(), rest.next(), rest.next()) {
            (Some(a), Some(b), None) if a != DVec3::ZERO && b != DVec3::ZERO => [a, b],
            _ => return None,
        };
        let cross = ends[0].cross(ends[1]);
        Some(Cone { ends, cross, normal: cross.try_normalize() })
    }

    /// The largest `w·x` over unit `x` in the cone: at the projection of `w` on the cone's plane
    /// when that lies inside, else at an end.
    fn most(&self, w: DVec3) -> f64 {
        let c = self.ends;
        let ends = more(c[0].dot(w), c[1].dot(w));
        let Some(normal) = self.normal else { return ends };
        let q = w - w.dot(normal) * normal;
        let inside = c[0].cross(q).dot(normal) >= 0.0 && q.cross(c[1]).dot(normal) >= 0.0;
        if inside && q.length_squared() > 0.0 { more(q.length(), ends) } else { ends }
    }

    /// `1 − cos γ` for the least angle `γ` between this cone and `other` (at the same corner),
    /// `None` where they touch: the closest pair has an end of one cone, or lies on both planes'
    /// common line.
    fn gap(&self, other: &Cone) -> Option<f64> {
        let (a, b) = (self, other);
        let mut cos_gamma = [a.most(b.ends[0]), a.most(b.ends[1]), b.most(a.ends[0]), b.most(a.ends[1])].into_iter().fold(f64::NEG_INFINITY, more);
        if let Some(line) = a.cross.cross(b.cross).try_normalize() {
            for l in [line, -line] {
                if a.most(l) >= 1.0 - 1e-12 && b.most(l) >= 1.0 - 1e-12 {
                    cos_gamma = 1.0;
                }
            }
        }
        let gap = 1.0 - (cos_gamma + 1e-12).min(1.0);
        (gap > 0.0).then_some(gap)
    }
}

/// The lower bound `dist(p, T') >= u·p − max_{y∈T'} u·y` of the distance to a competitor `T'`
/// along a unit direction `u`, with what it needs for every inset of `T`: `u·x − max_{y∈T'} u·y`
/// at `T`'s incentre and its least over `T`'s corners, and `k = 1 − u·sn` (`sn` is the side's
/// normal).
struct PlaneBound {
    at_incentre: f64,
    at_corners: f64,
    k: f64,
}

/// A direction `u`'s dot products with `T`'s incentre and the extremes over both triangles'
/// corners: the [`PlaneBound`]s along `u` and along `−u`.
#[derive(Clone, Copy)]
struct Along {
    at_incentre: f64,
    corners: [f64; 2],
    reach: [f64; 2],
}

impl Along {
    fn new(u: DVec3, t: &Triangle, incentre: DVec3, other: &Triangle) -> Along {
        let extremes = |p: &[DVec3; 3]| {
            let dots = p.map(|x| u.dot(x));
            [less(less(dots[0], dots[1]), dots[2]), more(more(dots[0], dots[1]), dots[2])]
        };
        Along { at_incentre: u.dot(incentre), corners: extremes(&t.p), reach: extremes(&other.p) }
    }

    /// The bound along `sign u` (`sign = ±1`) with its `k`.
    fn bound(&self, sign: f64, k: f64) -> PlaneBound {
        if sign > 0.0 {
            PlaneBound { at_incentre: self.at_incentre - self.reach[1], at_corners: self.corners[0] - self.reach[1], k }
        } else {
            PlaneBound { at_incentre: -self.at_incentre + self.reach[0], at_corners: -self.corners[1] + self.reach[0], k }
        }
    }
}

impl PlaneBound {
    /// The certified height over the inset at margin `f r`: the largest `H` with
    /// `t (1 − u·sn) <= u·x − max_{y∈T'} u·y` for all `x` in the inset and `t <= H`; 0 when it
    /// fails at `t = 0`, `∞` when unconstrained. The inset's corners are `incentre + (1 − f)(p_k −
    /// incentre)`, so the affine right-hand side's least over them is `(1 − f)` of the way from
    /// its value at the incentre to its least over `T`'s corners (rounded apart from the corners'
    /// own values by a few ulps of the coordinates, far below `epsilon`).
    fn certified_height(&self, f: f64, epsilon: f64) -> f64 {
        let lowest = self.at_incentre + (1.0 - f) * (self.at_corners - self.at_incentre) - 4.0 * epsilon;
        if self.k <= 1e-12 {
            // u = s n: the whole of T' is on the far side (up to rounding), for every height.
            return if lowest >= -8.0 * epsilon { f64::INFINITY } else { 0.0 };
        }
        if lowest < 0.0 {
            return 0.0;
        }
        lowest / self.k
    }
}
