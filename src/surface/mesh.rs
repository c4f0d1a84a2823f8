//! A triangle mesh as a mean surface: the exact signed distance to the mesh (closest point over a
//! bounding-volume hierarchy, sign from angle-weighted pseudo-normals, Bærentzen & Aanæs 2005),
//! the frame normal of Mitsuba 3's shading (the vertex normals interpolated at the closest point)
//! or, without vertex normals, the gradient of the distance, and Mitsuba's tangent `dp/du` (from
//! texture coordinates, else the Duff et al. 2017 basis of the face normal).
//!
//! Segment bounds are rigorous for any closed, consistently oriented mesh. Every triangle's
//! distance `d_T` is convex along a line (the distance to a convex set), so it lies above its
//! tangent at the segment start and below its chord; `|f| = min_T d_T` over the *candidates*,
//! the triangles that can be closest to some point of the segment (those within `|f(p)| + 2L` of
//! its start `p`). While the lower bound `A(s) = min_T tangent_T(s)` of `|f|` stays positive the
//! sign cannot change, so the segment is cut where it may cross the surface and each part gets
//! linear bounds. The frame normal's range follows from the candidates' vertex normals (or, for
//! the gradient, from the monotone derivatives of the `d_T`). A point query on the current
//! segment searches the candidates only.

use super::{Aabb, MeanSurface, SegmentBound, SurfacePoint};
use crate::error::{Error, ErrorKind, Result};
use glam::{DVec2, DVec3};
use std::collections::HashMap;

/// Triangles per leaf of the hierarchy.
const LEAF_SIZE: usize = 4;

/// Where on a triangle the closest point lies; decides which pseudo-normal gives the sign.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Feature {
    Face,
    /// Edge `i` runs from corner `i` to corner `(i + 1) % 3`.
    Edge(usize),
    Vertex(usize),
}

#[derive(Clone, Debug)]
struct Triangle {
    p: [DVec3; 3],
    /// Unit face normal from the winding; zero for a degenerate (zero-area) triangle.
    n: DVec3,
    /// Pseudo-normals of the edges (sum of the adjacent faces' normals) and of the corners
    /// (angle-weighted), for the sign of the distance.
    edge_pn: [DVec3; 3],
    vertex_pn: [DVec3; 3],
    /// Vertex (shading) normals, when the mesh has them.
    shading: Option<[DVec3; 3]>,
    /// A lower bound of `|Σ b_i n_i|` over the triangle's barycentric coordinates (0: none).
    shading_min_length: f64,
    /// A Lipschitz constant of `c ↦ Σ b_i(c) n_i` over the triangle (per unit of distance).
    shading_lipschitz: f64,
    /// Mitsuba's `dp/du` for this triangle.
    dpdu: DVec3,
}

#[derive(Clone, Copy, Debug)]
struct Node {
    min: DVec3,
    max: DVec3,
    /// Inner node: index of the left child (the right one follows it). Leaf: first triangle.
    first: u32,
    /// Triangles in a leaf; 0 for inner nodes.
    count: u32,
}

/// The closest point of a triangle to a query point.
#[derive(Clone, Copy, Debug)]
struct Closest {
    triangle: u32,
    point: DVec3,
    barycentric: DVec3,
    feature: Feature,
    distance_sq: f64,
}

/// A closed (or open) triangle mesh in world space; see the module documentation.
#[derive(Clone, Debug)]
pub struct TriangleMesh {
    triangles: Vec<Triangle>,
    /// The hierarchy's nodes; triangles are stored in leaf order.
    nodes: Vec<Node>,
    bounds: Aabb,
    /// Distances below this are rounding noise of the coordinates (1e-12 of the mesh's extent
    /// and offset): there the direction `p − c` is meaningless, and the bounds are padded by it.
    epsilon: f64,
}

/// Candidate triangles of the current segment (see the module documentation).
#[derive(Clone, Debug, Default)]
pub struct MeshCache {
    candidates: Vec<u32>,
}

impl TriangleMesh {
    /// Builds the surface from world-space positions, triangles (vertex indices, counter-clockwise
    /// seen from outside), and optional per-vertex unit normals and texture coordinates.
    pub fn new(positions: &[DVec3], indices: &[[u32; 3]], normals: Option<&[DVec3]>, uvs: Option<&[DVec2]>) -> Result<TriangleMesh> {
        let invalid = |m: String| Error::new(ErrorKind::InvalidArgument, m);
        if indices.is_empty() {
            return Err(invalid("the mesh has no triangles".into()));
        }
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(invalid(format!("vertex {i} is not finite: {}", positions[i])));
        }
        for (name, len) in [("normals", normals.map(<[_]>::len)), ("uvs", uvs.map(<[_]>::len))] {
            if let Some(len) = len {
                if len != positions.len() {
                    return Err(invalid(format!("{len} {name} for {} vertices", positions.len())));
                }
            }
        }
        if let Some(normals) = normals {
            if let Some(i) = normals.iter().position(|n| !n.is_finite() || (n.length() - 1.0).abs() > 1e-3) {
                return Err(invalid(format!("vertex normal {i} is not a finite unit vector: {}", normals[i])));
            }
        }
        if let Some(uvs) = uvs {
            if let Some(i) = uvs.iter().position(|uv| !uv.is_finite()) {
                return Err(invalid(format!("texture coordinate {i} is not finite: {}", uvs[i])));
            }
        }
        if let Some((t, tri)) = indices.iter().enumerate().find(|(_, tri)| tri.iter().any(|&v| v as usize >= positions.len())) {
            return Err(invalid(format!("triangle {t} refers to vertex {:?} of {}", tri, positions.len())));
        }

        // Weld vertices by exact position so that meshes split by normals or uvs still get the
        // pseudo-normals of their shared corners and edges.
        let mut weld: HashMap<[u64; 3], u32> = HashMap::new();
        let welded: Vec<u32> = positions
            .iter()
            .map(|p| {
                let key = [p.x, p.y, p.z].map(|c| (c + 0.0).to_bits()); // +0.0 merges -0.0
                let next = weld.len() as u32;
                *weld.entry(key).or_insert(next)
            })
            .collect();
        let corners = |tri: &[u32; 3]| tri.map(|v| welded[v as usize]);

        let face_normal = |tri: &[u32; 3]| {
            let [a, b, c] = tri.map(|v| positions[v as usize]);
            (b - a).cross(c - a).try_normalize().unwrap_or(DVec3::ZERO)
        };
        let mut vertex_pn = vec![DVec3::ZERO; weld.len()];
        let mut edge_pn: HashMap<(u32, u32), DVec3> = HashMap::new();
        for tri in indices {
            let n = face_normal(tri);
            if n == DVec3::ZERO {
                continue;
            }
            let w = corners(tri);
            for i in 0..3 {
                let (a, b, c) = (positions[tri[i] as usize], positions[tri[(i + 1) % 3] as usize], positions[tri[(i + 2) % 3] as usize]);
                let angle = (b - a).angle_between(c - a);
                if angle.is_finite() {
                    vertex_pn[w[i] as usize] += angle * n;
                }
                let (u, v) = (w[i], w[(i + 1) % 3]);
                *edge_pn.entry((u.min(v), u.max(v))).or_insert(DVec3::ZERO) += n;
            }
        }

        let mut triangles: Vec<Triangle> = indices
            .iter()
            .map(|tri| {
                let p = tri.map(|v| positions[v as usize]);
                let n = face_normal(tri);
                let w = corners(tri);
                let pn = |v: DVec3| v.try_normalize().unwrap_or(n);
                let edge = |i: usize| {
                    let (u, v) = (w[i], w[(i + 1) % 3]);
                    pn(edge_pn.get(&(u.min(v), u.max(v))).copied().unwrap_or(DVec3::ZERO))
                };
                let shading = normals.map(|ns| tri.map(|v| ns[v as usize].normalize()));
                let shading_min_length = shading.map_or(0.0, |ns| {
                    // |Σ b_i n_i| >= (Σ b_i n_i)·u >= min_i n_i·u for the unit mean direction u.
                    let u = (ns[0] + ns[1] + ns[2]).try_normalize().unwrap_or(DVec3::ZERO);
                    ns.iter().map(|n| n.dot(u)).fold(f64::INFINITY, f64::min).max(0.0)
                });
                Triangle {
                    p,
                    n,
                    edge_pn: [edge(0), edge(1), edge(2)],
                    vertex_pn: w.map(|v| pn(vertex_pn[v as usize])),
                    shading,
                    shading_min_length,
                    shading_lipschitz: shading.map_or(0.0, |ns| {
                        // ∇(Σ b_i n_i) = (n1 − n0) ⊗ ∇b1 + (n2 − n0) ⊗ ∇b2, |∇b1| = |e2|/2A,
                        // |∇b2| = |e1|/2A.
                        let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
                        let twice_area = e1.cross(e2).length();
                        if twice_area > 0.0 {
                            ((ns[1] - ns[0]).length() * e2.length() + (ns[2] - ns[0]).length() * e1.length()) / twice_area
                        } else {
                            f64::INFINITY
                        }
                    }),
                    dpdu: dpdu(&p, n, uvs.map(|uv| tri.map(|v| uv[v as usize]))),
                }
            })
            .collect();

        let mut order: Vec<u32> = (0..triangles.len() as u32).collect();
        let mut nodes = vec![Node { min: DVec3::ZERO, max: DVec3::ZERO, first: 0, count: 0 }];
        let centroids: Vec<DVec3> = triangles.iter().map(|t| (t.p[0] + t.p[1] + t.p[2]) / 3.0).collect();
        build(&mut nodes, &triangles, &centroids, &mut order, 0, 0, triangles.len());
        let mut sorted: Vec<Triangle> = order.iter().map(|&i| triangles[i as usize].clone()).collect();
        std::mem::swap(&mut triangles, &mut sorted);
        let bounds = Aabb { min: nodes[0].min, max: nodes[0].max };
        let epsilon = 1e-12 * (bounds.max - bounds.min).max_element().max(bounds.max.abs().max(bounds.min.abs()).max_element()).max(1e-300);
        Ok(TriangleMesh { triangles, nodes, bounds, epsilon })
    }

    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The closest point of the whole mesh to `p`.
    fn closest(&self, p: DVec3) -> Closest {
        let mut best = Closest { triangle: 0, point: DVec3::ZERO, barycentric: DVec3::ZERO, feature: Feature::Face, distance_sq: f64::INFINITY };
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = self.nodes[stack[top] as usize];
            // `>`, not `>=`: a triangle at the same distance with a smaller index wins ties.
            if box_distance_sq(&node, p) > best.distance_sq {
                continue;
            }
            if node.count > 0 {
                for i in node.first..node.first + node.count {
                    let c = closest_on_triangle(&self.triangles[i as usize], p, i);
                    if closer(&c, &best) {
                        best = c;
                    }
                }
            } else {
                // Visit the nearer child first.
                let (l, r) = (node.first, node.first + 1);
                let (dl, dr) = (box_distance_sq(&self.nodes[l as usize], p), box_distance_sq(&self.nodes[r as usize], p));
                let (near, far) = if dl <= dr { (l, r) } else { (r, l) };
                stack[top] = far;
                stack[top + 1] = near;
                top += 2;
            }
        }
        best
    }

    /// Every triangle within distance `radius` of `p`.
    fn within(&self, p: DVec3, radius: f64, out: &mut Vec<u32>) {
        out.clear();
        let r2 = radius * radius;
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = self.nodes[stack[top] as usize];
            if box_distance_sq(&node, p) > r2 {
                continue;
            }
            if node.count > 0 {
                out.extend((node.first..node.first + node.count).filter(|&i| closest_on_triangle(&self.triangles[i as usize], p, i).distance_sq <= r2));
            } else {
                stack[top] = node.first;
                stack[top + 1] = node.first + 1;
                top += 2;
            }
        }
    }

    /// The closest point among `candidates` (which must contain the mesh's closest point).
    fn closest_among(&self, p: DVec3, candidates: &[u32]) -> Closest {
        let mut best = Closest { triangle: 0, point: DVec3::ZERO, barycentric: DVec3::ZERO, feature: Feature::Face, distance_sq: f64::INFINITY };
        for &i in candidates {
            let c = closest_on_triangle(&self.triangles[i as usize], p, i);
            if closer(&c, &best) {
                best = c;
            }
        }
        best
    }

    /// The surface point of a closest-point result.
    fn surface_point(&self, p: DVec3, c: &Closest) -> SurfacePoint {
        let tri = &self.triangles[c.triangle as usize];
        let pseudo = match c.feature {
            Feature::Face => tri.n,
            Feature::Edge(i) => tri.edge_pn[i],
            Feature::Vertex(i) => tri.vertex_pn[i],
        };
        let offset = p - c.point;
        let distance = c.distance_sq.sqrt();
        let sign = if offset.dot(pseudo) >= 0.0 { 1.0 } else { -1.0 };
        let normal = match (tri.shading, c.feature) {
            (Some(ns), _) => (c.barycentric.x * ns[0] + c.barycentric.y * ns[1] + c.barycentric.z * ns[2]).try_normalize().unwrap_or(pseudo),
            // ∇(±|p − c|) over a face is its normal on both sides, exactly.
            (None, Feature::Face) => tri.n,
            (None, _) if distance > self.epsilon => sign * offset / distance,
            (None, _) => pseudo,
        };
        SurfacePoint { f: sign * distance, normal, tangent: tri.dpdu }
    }

    /// The range of `d·n` over the interpolated vertex normals `n = m/|m|`, `m = Σ b_i n_i`,
    /// at the closest points on triangle `i` of a segment of `length` whose start projects to
    /// barycentric `b0`; `None` without vertex normals (the frame is the distance gradient).
    /// The closest-point map is 1-Lipschitz, so those points lie within `length` of the first,
    /// where `m` changes by at most `shading_lipschitz × length`; the triangle's vertex normals
    /// bound it too.
    fn shading_cos_range(&self, i: u32, d: DVec3, b0: DVec3, length: f64) -> Option<[f64; 2]> {
        let tri = &self.triangles[i as usize];
        let ns = tri.shading?;
        let m0 = b0.x * ns[0] + b0.y * ns[1] + b0.z * ns[2];
        let spread = tri.shading_lipschitz * length;
        let dots = ns.map(|n| d.dot(n));
        let a = (d.dot(m0) - spread).max(dots[0].min(dots[1]).min(dots[2]));
        let b = (d.dot(m0) + spread).min(dots[0].max(dots[1]).max(dots[2]));
        let m = (m0.length() - spread).max(tri.shading_min_length);
        if m <= 0.0 {
            return Some([-1.0, 1.0]);
        }
        // d·m lies in [a, b]; dividing by |m| ∈ [m, 1] can magnify it up to 1/m.
        let lo = if a < 0.0 { a / m } else { a };
        let hi = if b > 0.0 { b / m } else { b };
        Some([lo.max(-1.0), hi.min(1.0)])
    }
}

/// A candidate triangle's distance at a point of a segment and its derivative along `d`, and
/// the signed distance to its plane with its derivative.
#[derive(Clone, Copy, Debug)]
struct Tangent {
    closest: Closest,
    distance: f64,
    slope: f64,
    /// False when rounding makes `slope` too inaccurate for a supporting line.
    reliable: bool,
    plane: f64,
    plane_slope: f64,
}

/// Lower lines of a triangle's convex distance `d_T` along a segment: the tangent at a point
/// of it (`d_T` is convex) and `±` the signed plane distance (`d_T >= |plane|`, exact over the
/// triangle's interior). As (value at 0, slope), lowered by `eps` for rounding.
fn lower_lines(t: &Tangent, at: f64, eps: f64) -> [(f64, f64); 3] {
    // Without a reliable derivative, the Lipschitz line falling away from `at` into the segment.
    let tangent_slope = if t.reliable { t.slope } else if at == 0.0 { -1.0 } else { 1.0 };
    [(t.distance, tangent_slope), (t.plane, t.plane_slope), (-t.plane, -t.plane_slope)].map(|(v, k)| (v - k * at - eps, k))
}

/// How far from `s = 0` every candidate keeps a positive lower line (so `|f| > 0`): for each
/// candidate the farthest zero of its lines that start positive (`∞` if one does not decrease),
/// then the nearest over candidates. `None` when some candidate has no line positive at 0.
fn positive_until(lines: &[[(f64, f64); 3]]) -> Option<f64> {
    lines.iter().try_fold(f64::INFINITY, |reach: f64, ls| {
        let own = ls.iter().filter(|(v, _)| *v > 0.0).map(|&(v, k)| if k < 0.0 { v / -k } else { f64::INFINITY }).fold(f64::NEG_INFINITY, f64::max);
        (own > 0.0).then_some(reach.min(own))
    })
}

/// The line (of both ends' lower lines) with the largest minimum over `[0, length]`: the bound
/// is a minimum over triangles, so a line that dips anywhere costs there.
fn best_lower_line(start: &Tangent, end: &Tangent, length: f64, eps: f64) -> (f64, f64) {
    lower_lines(start, 0.0, eps)
        .into_iter()
        .chain(std::iter::once(lower_lines(end, length, eps)[0]))
        .max_by(|a, b| a.0.min(a.0 + a.1 * length).total_cmp(&b.0.min(b.0 + b.1 * length)))
        .expect("four lines")
}

/// The elements of `v` whose flag in `keep` is set.
fn retained<T>(v: Vec<T>, keep: &[bool]) -> Vec<T> {
    v.into_iter().zip(keep).filter(|(_, k)| **k).map(|(x, _)| x).collect()
}

/// The closest point among the candidates' tangents.
fn closest_of(tangents: &[Tangent]) -> Closest {
    tangents.iter().map(|t| t.closest).reduce(|best, c| if closer(&c, &best) { c } else { best }).expect("candidates are not empty")
}

impl TriangleMesh {
    /// `d_T(q)` and `d/ds d_T(q + s d)` for every candidate `T`. At distance 0 the triangle's
    /// plane gives the slope of a supporting line of the convex `d_T`.
    ///
    /// The derivative is the direction `(q − c)/|q − c|`, whose rounding error (about
    /// `1e-15 × coordinates / distance`) would tilt the tangent by more than `epsilon` over a
    /// segment of `length` when the distance is below `2e-3 length`: there the derivative is
    /// marked unreliable (the tangent is replaced by the Lipschitz line, the gradient's range by
    /// `[-1, 1]`).
    fn tangents(&self, q: DVec3, d: DVec3, candidates: &[u32], length: f64) -> Vec<Tangent> {
        candidates
            .iter()
            .map(|&i| {
                let tri = &self.triangles[i as usize];
                let closest = closest_on_triangle(tri, q, i);
                let distance = closest.distance_sq.sqrt();
                let plane = tri.n.dot(q - tri.p[0]);
                let (distance, slope, reliable) = if distance <= self.epsilon {
                    // On the triangle: the plane's slope gives a supporting line.
                    (0.0, d.dot(tri.n).abs(), true)
                } else if closest.feature == Feature::Face {
                    // Over the face, d_T = |plane|: the derivative without the rounding of p − c.
                    (distance, plane.signum() * d.dot(tri.n), true)
                } else {
                    (distance, d.dot(q - closest.point) / distance, distance >= 2e-3 * length)
                };
                Tangent { closest, distance, slope, reliable, plane, plane_slope: tri.n.dot(d) }
            })
            .collect()
    }
}

impl MeanSurface for TriangleMesh {
    type Cache = MeshCache;

    fn point(&self, p: DVec3) -> Result<SurfacePoint> {
        Ok(self.surface_point(p, &self.closest(p)))
    }

    fn point_on_segment(&self, p: DVec3, cache: &MeshCache) -> Result<SurfacePoint> {
        if cache.candidates.is_empty() {
            return self.point(p);
        }
        Ok(self.surface_point(p, &self.closest_among(p, &cache.candidates)))
    }

    fn bound(&self, start: &SurfacePoint, p: DVec3, d: DVec3, length: f64, cache: &mut MeshCache) -> Result<SegmentBound> {
        // Triangles that can be closest to a point q of the segment: |f(q)| <= |f(p)| + L and
        // |q − p| <= L, so they lie within |f(p)| + 2L of p (with a relative margin for rounding).
        let radius = (start.f.abs() + 2.0 * length) * (1.0 + 1e-9) + 1e-12;
        self.within(p, radius, &mut cache.candidates);
        if cache.candidates.is_empty() {
            // Only rounding can get here (the closest triangle is within |f(p)|).
            cache.candidates.push(self.closest(p).triangle);
        }
        let first = self.tangents(p, d, &cache.candidates, length);
        let mut last = self.tangents(p + length * d, d, &cache.candidates, length);
        let f_end = self.surface_point(p + length * d, &closest_of(&last)).f;

        // Lower lines of |f(p + s d)| = min_T d_T: per candidate lines below d_T, lowered by the
        // coordinates' rounding (about `epsilon`). The sign of f can only change where every
        // line of some candidate is <= 0.
        let eps = self.epsilon;
        let start_lines: Vec<[(f64, f64); 3]> = first.iter().map(|t| lower_lines(t, 0.0, eps)).collect();
        let end_lines: Vec<[(f64, f64); 3]> = last.iter().map(|t| lower_lines(t, length, eps)).collect();
        // Within |f(p)| of the start the sign cannot change either (f is 1-Lipschitz).
        let lipschitz_reach = start.f.abs() * (1.0 - 1e-12);
        // A cut shorter than this is not worth a segment of its own.
        let min_piece = 1e-6 * length;
        let (piece, sign) = if let Some(first_zero) = positive_until(&start_lines) {
            (first_zero.max(lipschitz_reach).min(length), start.f.signum())
        } else {
            // Mirrored: from the end, the sign is that of f(L) after the last zero.
            let mirrored: Vec<[(f64, f64); 3]> = end_lines.iter().map(|ls| ls.map(|(v, k)| (v + k * length, -k))).collect();
            match positive_until(&mirrored).map(|reach| length - reach) {
                Some(last_zero) if last_zero <= lipschitz_reach.max(3.0 * eps) => (length, f_end.signum()),
                Some(last_zero) if last_zero < length - min_piece => (last_zero, 0.0),
                _ => (length, 0.0),
            }
        };
        // A cut too close to the start: take a short piece of either sign instead.
        let (piece, sign) = if piece < min_piece { (min_piece.min(length), 0.0) } else { (piece, sign) };
        if piece < length {
            last = self.tangents(p + piece * d, d, &cache.candidates, piece);
        }
        // On the piece, the best of all four lines per candidate.
        let lines: Vec<(f64, f64)> = first.iter().zip(&last).map(|(a, b)| best_lower_line(a, b, piece, eps)).collect();
        // The chord of one triangle bounds min_T d_T from above; take the closest overall.
        let k = (0..first.len()).min_by(|&x, &y| (first[x].distance + last[x].distance).total_cmp(&(first[y].distance + last[y].distance))).expect("candidates");
        let chord = [first[k].distance + eps, last[k].distance + eps];
        // A candidate whose lower line stays above that chord is never the closest on the piece:
        // drop it (from the bounds, and from the point queries on this segment).
        let keep: Vec<bool> = lines.iter().map(|(v, slope)| !(*v > chord[0] && v + slope * piece > chord[1])).collect();
        let mut j = 0;
        cache.candidates.retain(|_| {
            j += 1;
            keep[j - 1]
        });
        let (first, last) = (retained(first, &keep), retained(last, &keep));
        let lines = retained(lines, &keep);
        let a_at = |s: f64| lines.iter().map(|(v, k)| v + k * s).fold(f64::INFINITY, f64::min);
        let (a0, a1) = (a_at(0.0).max(-eps), a_at(piece).max(-eps));
        let chord = [chord[0] - eps, chord[1] - eps];
        let (f_lo, f_hi) = if sign > 0.0 {
            ([a0, a1], chord)
        } else if sign < 0.0 {
            ([-chord[0], -chord[1]], [-a0, -a1])
        } else {
            // Either sign: f >= min(A, −chord), concave so above its own chord; f <= max(chord,
            // −A), convex so below its chord.
            ([a0.min(-chord[0]), a1.min(-chord[1])], [chord[0].max(-a0), chord[1].max(-a1)])
        };

        // The range of d·n for the frame normal along the piece.
        let mut cos = [f64::INFINITY, f64::NEG_INFINITY];
        for (j, &i) in cache.candidates.iter().enumerate() {
            let range = self.shading_cos_range(i, d, first[j].closest.barycentric, piece).unwrap_or_else(|| {
                // The distance gradient. Over a face it is the face normal on both sides, and the
                // face region is convex: with both ends there, so is the whole piece.
                if first[j].closest.feature == Feature::Face && last[j].closest.feature == Feature::Face {
                    let c = d.dot(self.triangles[i as usize].n);
                    return [c, c];
                }
                // Elsewhere f' = ±d_T', and d_T' increases along the piece.
                if first[j].distance == 0.0 || last[j].distance == 0.0 || !first[j].reliable || !last[j].reliable {
                    return [-1.0, 1.0];
                }
                let (k0, k1) = (first[j].slope, last[j].slope);
                // Monotone in exact arithmetic; order the ends against rounding.
                let (k0, k1) = (k0.min(k1), k0.max(k1));
                if sign > 0.0 {
                    [k0, k1]
                } else if sign < 0.0 {
                    [-k1, -k0]
                } else {
                    [k0.min(-k1), k1.max(-k0)]
                }
            });
            cos = [cos[0].min(range[0]), cos[1].max(range[1])];
        }
        // Padding by the rounding scale of the coordinates.
        let cos = [(cos[0] - 1e-12).clamp(-1.0, 1.0), (cos[1] + 1e-12).clamp(-1.0, 1.0)];
        let pad = |v: [f64; 2], by: f64| [v[0] + by, v[1] + by];
        let end = self.surface_point(p + piece * d, &closest_of(&last));
        Ok(SegmentBound { length: piece, f_lo: pad(f_lo, -4.0 * eps), f_hi: pad(f_hi, 4.0 * eps), cos, end: Some(end) })
    }

    fn bounding_box(&self) -> Aabb {
        self.bounds
    }
}

/// Mitsuba 3's `dp/du` of a triangle: from its texture coordinates when they are not degenerate,
/// otherwise the first vector of the Duff et al. 2017 basis of the face normal (glam's
/// `any_orthonormal_pair` is that construction, as is Mitsuba's `coordinate_system`).
fn dpdu(p: &[DVec3; 3], n: DVec3, uv: Option<[DVec2; 3]>) -> DVec3 {
    if let Some(uv) = uv {
        let (duv0, duv1) = (uv[1] - uv[0], uv[2] - uv[0]);
        let det = duv0.x * duv1.y - duv0.y * duv1.x;
        if det != 0.0 {
            return (duv1.y * (p[1] - p[0]) - duv0.y * (p[2] - p[0])) / det;
        }
    }
    if n == DVec3::ZERO {
        return DVec3::ZERO;
    }
    n.any_orthonormal_pair().0
}

/// The order of closest points: by distance, ties (points on a medial surface) to the smaller
/// triangle index, so that every search returns the same triangle, hence the same frame.
fn closer(a: &Closest, b: &Closest) -> bool {
    a.distance_sq < b.distance_sq || (a.distance_sq == b.distance_sq && a.triangle < b.triangle)
}

fn box_distance_sq(node: &Node, p: DVec3) -> f64 {
    let q = p.clamp(node.min, node.max);
    (p - q).length_squared()
}

/// Fills node `slot` with the hierarchy over `order[first..first + count]`: median splits of the
/// centroids along the longest axis of their bounds, children allocated in pairs.
fn build(nodes: &mut Vec<Node>, triangles: &[Triangle], centroids: &[DVec3], order: &mut [u32], slot: usize, first: usize, count: usize) {
    let (mut min, mut max) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    let (mut cmin, mut cmax) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for &i in &order[first..first + count] {
        for v in triangles[i as usize].p {
            min = min.min(v);
            max = max.max(v);
        }
        cmin = cmin.min(centroids[i as usize]);
        cmax = cmax.max(centroids[i as usize]);
    }
    if count <= LEAF_SIZE {
        nodes[slot] = Node { min, max, first: first as u32, count: count as u32 };
        return;
    }
    let extent = cmax - cmin;
    let axis = if extent.x >= extent.y && extent.x >= extent.z { 0 } else if extent.y >= extent.z { 1 } else { 2 };
    let half = count / 2;
    order[first..first + count].select_nth_unstable_by(half, |&a, &b| centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis]));
    let left = nodes.len();
    nodes.extend([Node { min, max, first: 0, count: 0 }; 2]);
    nodes[slot] = Node { min, max, first: left as u32, count: 0 };
    build(nodes, triangles, centroids, order, left, first, half);
    build(nodes, triangles, centroids, order, left + 1, first + half, count - half);
}

/// The closest point of triangle `t` to `p` (Ericson, *Real-Time Collision Detection*, 5.1.5),
/// with its barycentric coordinates and feature. A degenerate triangle is treated as its edges.
fn closest_on_triangle(t: &Triangle, p: DVec3, index: u32) -> Closest {
    let [a, b, c] = t.p;
    let make = |point: DVec3, bary: DVec3, feature: Feature| Closest { triangle: index, point, barycentric: bary, feature, distance_sq: (p - point).length_squared() };
    if t.n == DVec3::ZERO {
        return (0..3)
            .map(|i| {
                let (u, v) = (t.p[i], t.p[(i + 1) % 3]);
                let e = v - u;
                let s = if e.length_squared() > 0.0 { ((p - u).dot(e) / e.length_squared()).clamp(0.0, 1.0) } else { 0.0 };
                let mut bary = DVec3::ZERO;
                bary[i] = 1.0 - s;
                bary[(i + 1) % 3] = s;
                make(u + s * e, bary, Feature::Edge(i))
            })
            .min_by(|x, y| x.distance_sq.total_cmp(&y.distance_sq))
            .expect("three edges");
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
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    make(a + ab * v + ac * w, DVec3::new(1.0 - v - w, v, w), Feature::Face)
}
