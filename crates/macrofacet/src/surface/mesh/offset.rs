//! A mesh's own enclosure: the mesh with its vertices moved out along their angle-weighted
//! normals, far enough that every face of the result lies at least `level` from the mesh, then
//! verified. It has the mesh's triangles (a voxel enclosure of the thin torus anchor has 33 times
//! as many) and lies within about `level / cos θ` of the level set, where θ is the largest angle
//! between a vertex's normal and its faces' (a cell diagonal for the voxel one: 13 times the thin
//! torus's shell), so that a ray enters the medium where the shell begins instead of stepping
//! down across the gap (seeds/000 Sec. 4: the medium's region is `f < kσ`).
//!
//! Offsetting a vertex by `h = L / min cos` puts it at least `L` above the planes of its faces
//! (its plane distance to face `g` is `h n_v·n_g`), and since the plane distance is linear over a
//! triangle, every offset face lies at least `L` above the planes of the faces around it. That
//! alone proves nothing about the rest of the mesh, nor about the offset faces' arrangement, so
//! the result is kept only when it passes three checks; otherwise the caller builds the voxel
//! enclosure ([`crate::surface::enclosure`]):
//! - *clearance*: every offset face lies at least `level` (plus a margin) from every face of the
//!   mesh, by the plane bound or else the exact triangle–triangle distance;
//! - *embedding*: no two offset faces meet beyond the edge or vertex they share, and none turned
//!   over (its normal within 60° of its face's);
//! - *outside, around*: each connected part of the offset lies outside the mesh (`f >= level` at
//!   one of its vertices; with the clearance, `|f| >= level` all over it, so `f` cannot change
//!   sign on it) and winds once around a vertex of the mesh's part (generalized winding number,
//!   van Oosterom & Strackee 1983).
//!
//! A closed, embedded surface that avoids the region `f < level` (each of whose connected parts
//! holds a part of the mesh) and winds once around a point of each encloses all of it: that is
//! what a host's ray tracer needs.

use super::bvh::Bvh;
use super::edge::segment_distance;
use super::triangle::Triangle;
use super::TriangleMesh;
use crate::parallel;
use crate::surface::{Enclosure, MeanSurface};
use glam::DVec3;
use smallvec::SmallVec;
use std::f64::consts::PI;

/// The offset stops where a vertex's normal leaves one of its faces' by more than this cosine
/// (78°): a spike or a blade, whose offset would have to grow by more than 5 times the level.
const MIN_COS: f64 = 0.2;
/// Offset faces within this many triangles of one another (their own, and the mesh's) are more
/// than a search can compare cheaply: the voxel enclosure then.
const MAX_NEIGHBOURS: usize = 256;
/// Connected parts of the mesh each cost one pass over the triangles for the winding number;
/// beyond this many the voxel enclosure is cheaper.
const MAX_PARTS: usize = 64;
/// Offset faces whose normals differ by more than this cosine across their shared edge have
/// folded onto each other.
const FOLDED_COS: f64 = -0.9;
/// An offset face whose normal turned from its face's by more than this cosine is rejected.
const TURNED_COS: f64 = 0.5;

impl TriangleMesh {
    /// The offset enclosure of `f < level` (see the module documentation), or `None` when it
    /// does not verify (or `level <= 0`): then the voxel enclosure. The offset clears the mesh by
    /// `level` plus a margin of `1e-3 level` and of 16 single-precision ulps of the largest
    /// coordinate, so that a host's `f32` copy of the vertices still encloses the region.
    pub(crate) fn offset_enclosure(&self, level: f64) -> Option<Enclosure> {
        if !(level > 0.0 && level.is_finite()) {
            return None;
        }
        let magnitude = self.bounds.min.abs().max(self.bounds.max.abs()).max_element();
        let required = level + 1e-3 * level + 16.0 * f64::from(f32::EPSILON) * magnitude;
        // Offset for twice the margin; the checks ask for one (the rest absorbs their rounding).
        let target = 2.0 * required - level;

        let (vertices, normals) = self.welded_vertices();
        // Per vertex: the least cosine between its normal and its faces' normals.
        let mut least_cos = vec![f64::INFINITY; vertices.len()];
        for (t, corners) in self.triangles.iter().zip(&self.corners) {
            if t.n == DVec3::ZERO {
                continue;
            }
            for &v in corners {
                least_cos[v as usize] = least_cos[v as usize].min(normals[v as usize].dot(t.n));
            }
        }
        let mut offset = vertices.clone();
        // The largest offset: a point of an offset face lies within it of its mesh face.
        let mut reach = 0.0f64;
        for (v, q) in offset.iter_mut().enumerate() {
            let c = least_cos[v];
            if c == f64::INFINITY {
                continue; // no face: not part of the mesh (or only of degenerate faces)
            }
            if !(c >= MIN_COS) {
                return None;
            }
            *q += (target / c) * normals[v];
            reach = reach.max(target / c);
        }
        if offset.iter().any(|q| !q.is_finite()) {
            return None;
        }
        let faces: Vec<Triangle> = self
            .corners
            .iter()
            .map(|c| {
                let p = c.map(|v| offset[v as usize]);
                Triangle::new(p, (p[1] - p[0]).cross(p[2] - p[0]).try_normalize().unwrap_or(DVec3::ZERO))
            })
            .collect();
        // Turned over: the offset face must face the way its face does.
        if self.triangles.iter().zip(&faces).any(|(t, o)| t.n != DVec3::ZERO && !(o.n.dot(t.n) >= TURNED_COS)) {
            return None;
        }
        let cleared = parallel::map(faces.len(), self.threads, Vec::new, |near, i| self.clears(&faces[i], required, near));
        if !cleared.iter().all(|&c| c) {
            return None;
        }
        if !embedded(&faces, &self.corners, magnitude, self.threads) {
            return None;
        }
        if !self.encloses(&faces, &vertices, &offset, level) {
            return None;
        }
        // The vertices the faces use, numbered in order of first use.
        let mut number = vec![u32::MAX; offset.len()];
        // Points between the mesh and the offset lie in the prisms between each face and its
        // offset (the offset is embedded): within `reach` of a face. The margin covers a host's
        // rounding to f32 (of the vertices, and of a ray's origin).
        let mut out = Enclosure { exit_level: reach + (required - level), ..Default::default() };
        for c in &self.corners {
            out.triangles.push(c.map(|v| {
                if number[v as usize] == u32::MAX {
                    number[v as usize] = out.positions.len() as u32;
                    out.positions.push(offset[v as usize]);
                }
                number[v as usize]
            }));
        }
        Some(out)
    }

    /// The welded vertices (by id, `self.corners`' numbering) and their angle-weighted normals,
    /// from the triangles' corners and pseudo-normals (where a vertex's faces' normals cancel,
    /// its corners fall back to their faces' normals, and some face then leaves it by more than
    /// 90°: no offset, as with no normal at all).
    fn welded_vertices(&self) -> (Vec<DVec3>, Vec<DVec3>) {
        let count = self.corners.iter().flatten().max().map_or(0, |&v| v as usize + 1);
        let (mut vertices, mut normals) = (vec![DVec3::ZERO; count], vec![DVec3::ZERO; count]);
        for ((t, a), corners) in self.triangles.iter().zip(&self.attributes).zip(&self.corners) {
            for k in 0..3 {
                vertices[corners[k] as usize] = t.p[k];
                normals[corners[k] as usize] = a.vertex_pn[k];
            }
        }
        (vertices, normals)
    }

    /// True when the offset face `o` lies at least `required` from every face of the mesh.
    fn clears(&self, o: &Triangle, required: f64, near: &mut Vec<u32>) -> bool {
        if !self.bvh.within(&self.triangles, o.centre, o.radius + required, MAX_NEIGHBOURS, near) {
            return false;
        }
        near.iter().all(|&g| at_least_apart(o, &self.triangles[g as usize], required))
    }

    /// True when each connected part of the offset mesh `faces` (vertices `offset`, moved from
    /// the mesh's `vertices`) lies outside the mesh, at `f >= level` at its first vertex, and
    /// winds once around that vertex of the mesh (where `f = 0 < level`).
    fn encloses(&self, faces: &[Triangle], vertices: &[DVec3], offset: &[DVec3], level: f64) -> bool {
        // Parts by union–find over the faces' corners.
        let mut parent: Vec<u32> = (0..vertices.len() as u32).collect();
        fn root(parent: &mut [u32], mut v: u32) -> u32 {
            while parent[v as usize] != v {
                parent[v as usize] = parent[parent[v as usize] as usize];
                v = parent[v as usize];
            }
            v
        }
        for c in &self.corners {
            for k in 1..3 {
                let (a, b) = (root(&mut parent, c[0]), root(&mut parent, c[k]));
                parent[a.max(b) as usize] = a.min(b);
            }
        }
        let mut tested = Vec::new();
        for c in &self.corners {
            let r = root(&mut parent, c[0]);
            if tested.contains(&r) {
                continue;
            }
            if tested.len() == MAX_PARTS {
                return false;
            }
            tested.push(r);
            if !self.point(offset[c[0] as usize]).is_ok_and(|q| q.f >= level) {
                return false;
            }
            let p = vertices[c[0] as usize];
            let winding: f64 = faces.iter().map(|o| solid_angle(o, p)).sum::<f64>() / (4.0 * PI);
            if !((winding - 1.0).abs() < 0.25) {
                return false;
            }
        }
        true
    }
}

/// True when no two of the offset `faces` meet beyond the corners they share (`corners`: their
/// vertex ids): apart, they keep more than a rounding distance; sharing a vertex, neither's
/// opposite edge reaches the other (two triangles that share one vertex and overlap along a
/// segment from it have the segment's far end on one's opposite edge); sharing an edge, they have
/// not folded onto each other. Each face's pairs on one of up to `threads` threads (all of them
/// checked, as the clearance's: a failing offset costs what a passing one does).
fn embedded(faces: &[Triangle], corners: &[[u32; 3]], magnitude: f64, threads: usize) -> bool {
    let apart = 1e-9 * magnitude;
    let (bvh, order) = Bvh::build(faces);
    let sorted: Vec<Triangle> = order.iter().map(|&i| faces[i as usize].clone()).collect();
    let embedded_at = parallel::map(faces.len(), threads, Vec::new, |near, a| {
        let fa = &faces[a];
        if !bvh.within(&sorted, fa.centre, fa.radius + apart, MAX_NEIGHBOURS, near) {
            return false;
        }
        near.iter().map(|&k| order[k as usize] as usize).filter(|&b| b > a).all(|b| {
            let fb = &faces[b];
            // (On the stack: this runs for every pair of neighbouring faces.)
            let shared: SmallVec<[usize; 3]> = (0..3).filter(|&i| corners[b].contains(&corners[a][i])).collect();
            match shared.len() {
                0 => at_least_apart(fa, fb, apart),
                1 => {
                    let opposite = |c: &[u32; 3], f: &Triangle, v: u32| {
                        let i = c.iter().position(|&x| x == v).unwrap_or(0);
                        (f.p[(i + 1) % 3], f.p[(i + 2) % 3])
                    };
                    let v = corners[a][shared[0]];
                    let (a0, a1) = opposite(&corners[a], fa, v);
                    let (b0, b1) = opposite(&corners[b], fb, v);
                    // An edge wholly beyond the other face's plane is apart from it (most of a smooth
                    // mesh's fans): segment distances only for the rest.
                    (beyond_plane(fb, &[a0, a1], apart) || segment_distance(fb, a0, a1) > apart) && (beyond_plane(fa, &[b0, b1], apart) || segment_distance(fa, b0, b1) > apart)
                }
                2 => fa.n.dot(fb.n) > FOLDED_COS,
                _ => false,
            }
        })
    });
    embedded_at.iter().all(|&e| e)
}

/// Whether triangles `a` and `b` lie at least `gap` apart: one wholly beyond the other's plane by
/// `gap` (on either side; the distance to a triangle is at least that to its plane), else by
/// their distance.
fn at_least_apart(a: &Triangle, b: &Triangle, gap: f64) -> bool {
    beyond_plane(b, &a.p, gap) || beyond_plane(a, &b.p, gap) || triangle_distance(a, b) >= gap
}

/// Whether `points` all lie beyond the plane of `t` by `gap`, on one side: their convex hull (a
/// triangle, an edge) is then at least `gap` from `t`, whose distance is at least its plane's.
fn beyond_plane(t: &Triangle, points: &[DVec3], gap: f64) -> bool {
    if t.n == DVec3::ZERO {
        return false;
    }
    let (mut above, mut below) = (true, true);
    for q in points {
        let h = t.n.dot(*q - t.p[0]);
        above &= h >= gap;
        below &= h <= -gap;
    }
    above || below
}

/// The distance between two triangles: where they do not meet, the closest pair has a point on
/// an edge of one of them; where they do, an edge of one crosses the other.
fn triangle_distance(a: &Triangle, b: &Triangle) -> f64 {
    (0..3).map(|k| segment_distance(b, a.p[k], a.p[(k + 1) % 3]).min(segment_distance(a, b.p[k], b.p[(k + 1) % 3]))).fold(f64::INFINITY, f64::min)
}

/// The signed solid angle of triangle `t` seen from `p` (positive where `p` lies behind its
/// counter-clockwise face), van Oosterom & Strackee (1983).
fn solid_angle(t: &Triangle, p: DVec3) -> f64 {
    let [a, b, c] = t.p.map(|q| q - p);
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let numerator = a.dot(b.cross(c));
    let denominator = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    2.0 * numerator.atan2(denominator)
}

#[cfg(test)]
mod tests {
    use super::super::triangle::{closest_on_triangle, from_corners};
    use super::*;
    use crate::rng::Pcg32;

    /// The triangle–triangle distance is the least over dense samples of one triangle against
    /// the other (which can only be larger), and 0 for triangles that cross.
    #[test]
    fn triangle_distance_matches_sampling() {
        let mut rng = Pcg32::new(3, 8);
        let mut point = |scale: f64| DVec3::new(rng.next_f64() - 0.5, rng.next_f64() - 0.5, rng.next_f64() - 0.5) * scale;
        for k in 0..300 {
            let (a, b) = (from_corners([point(2.0), point(2.0), point(2.0)]), from_corners([point(3.0), point(3.0), point(3.0)]));
            let exact = triangle_distance(&a, &b);
            let n = 60;
            let mut sampled = f64::INFINITY;
            for i in 0..=n {
                for j in 0..=n - i {
                    let q = a.p[0] + (i as f64 / n as f64) * (a.p[1] - a.p[0]) + (j as f64 / n as f64) * (a.p[2] - a.p[0]);
                    sampled = sampled.min(closest_on_triangle(&b, q, 0).distance_sq.sqrt());
                }
            }
            let step = (a.p[1] - a.p[0]).length().max((a.p[2] - a.p[0]).length()) / n as f64;
            assert!(exact <= sampled + 1e-12 && exact >= sampled - step, "case {k}: {exact} against the sampled {sampled}");
        }
        let flat = from_corners([DVec3::ZERO, DVec3::X, DVec3::Y]);
        let through = from_corners([DVec3::new(0.2, 0.2, -1.0), DVec3::new(0.2, 0.2, 1.0), DVec3::new(2.0, 2.0, 0.0)]);
        assert!(triangle_distance(&flat, &through) < 1e-15);
    }

    /// Apart, sharing a vertex, sharing an edge: embedded or not.
    #[test]
    fn embedding_finds_faces_that_meet() {
        let t = |p: [DVec3; 3]| from_corners(p);
        let (o, x, y, z) = (DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z);
        let cases = [
            // Apart, then crossing.
            (vec![t([o, x, y]), t([o + z, x + z, y + z])], vec![[0, 1, 2], [3, 4, 5]], true),
            (vec![t([o, x, y]), t([DVec3::new(0.2, 0.2, -1.0), DVec3::new(0.2, 0.2, 1.0), DVec3::new(2.0, 2.0, 0.0)])], vec![[0, 1, 2], [3, 4, 5]], false),
            // Sharing vertex 0: a fan, then one folded through the other.
            (vec![t([o, x, y]), t([o, -x, -y])], vec![[0, 1, 2], [0, 3, 4]], true),
            (vec![t([o, x, y]), t([o, DVec3::new(1.0, 0.5, 0.3), DVec3::new(1.0, 0.5, -0.3)])], vec![[0, 1, 2], [0, 3, 4]], false),
            // Sharing edge 0–1: a hinge, then folded flat onto the first.
            (vec![t([o, x, y]), t([x, o, -y + z])], vec![[0, 1, 2], [1, 0, 3]], true),
            (vec![t([o, x, y]), t([x, o, DVec3::new(0.4, 0.4, 1e-3)])], vec![[0, 1, 2], [1, 0, 3]], false),
        ];
        for (k, (faces, corners, expected)) in cases.iter().enumerate() {
            assert_eq!(embedded(faces, corners, 1.0, 1), *expected, "case {k}");
        }
    }

    /// The winding number of a closed tetrahedron is 1 inside and 0 outside.
    #[test]
    fn solid_angles_wind_once_around_the_inside() {
        let (o, x, y, z) = (DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z);
        let faces = [[o, y, x], [o, x, z], [o, z, y], [x, y, z]].map(from_corners);
        let winding = |p: DVec3| faces.iter().map(|f| solid_angle(f, p)).sum::<f64>() / (4.0 * PI);
        assert!((winding(DVec3::splat(0.2)) - 1.0).abs() < 1e-12);
        assert!(winding(DVec3::splat(2.0)).abs() < 1e-12);
    }

    /// Faces that clear the mesh but lie inside it (a cube's shrunk copy) do not enclose the
    /// region; the grown copy does.
    #[test]
    fn an_offset_inside_the_mesh_does_not_enclose() {
        let corners: Vec<DVec3> = (0..8).map(|i| DVec3::new([-1.0, 1.0][i & 1], [-1.0, 1.0][(i >> 1) & 1], [-1.0, 1.0][i >> 2])).collect();
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let triangles: Vec<[u32; 3]> = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
        let cube = TriangleMesh::new(&corners, &triangles, None, None, 1, f64::INFINITY).unwrap();
        for (scale, expected) in [(0.7, false), (1.3, true)] {
            let (vertices, _) = cube.welded_vertices();
            let offset: Vec<DVec3> = vertices.iter().map(|&v| v * scale).collect();
            let faces: Vec<Triangle> = cube.corners.iter().map(|c| from_corners(c.map(|v| offset[v as usize]))).collect();
            assert_eq!(cube.encloses(&faces, &vertices, &offset, 0.1), expected, "scale {scale}");
        }
    }

    /// A spike (a vertex whose normal leaves a face by more than 78°) and a level that is not
    /// positive get no offset enclosure; a tetrahedron does, clearing the level.
    #[test]
    fn offset_needs_blunt_vertices_and_a_positive_level() {
        let tetrahedron = |apex: f64| {
            let p = [DVec3::new(1.0, 0.0, 0.0), DVec3::new(-0.5, 0.8660254, 0.0), DVec3::new(-0.5, -0.8660254, 0.0), DVec3::new(0.0, 0.0, apex)];
            TriangleMesh::new(&p, &[[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]], None, None, 1, f64::INFINITY).unwrap()
        };
        let blunt = tetrahedron(1.0);
        let e = blunt.offset_enclosure(0.01).expect("a blunt tetrahedron offsets");
        assert_eq!((e.positions.len(), e.triangles.len(), e.cell), (4, 4, 0.0));
        for q in &e.positions {
            assert!(blunt.point(*q).unwrap().f >= 0.01);
        }
        assert!(blunt.offset_enclosure(0.0).is_none() && blunt.offset_enclosure(-0.1).is_none());
        assert!(tetrahedron(40.0).offset_enclosure(0.01).is_none());
    }
}
