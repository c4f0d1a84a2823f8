//! A triangle mesh as a mean surface: the exact signed distance to the mesh (closest point over a
//! bounding-volume hierarchy, sign from angle-weighted pseudo-normals, Bærentzen & Aanæs 2005),
//! the frame normal of Mitsuba 3's shading (the vertex normals interpolated at the closest point)
//! or, without vertex normals, the gradient of the distance, and Mitsuba's tangent `dp/du` (from
//! texture coordinates, else the Duff et al. 2017 basis of the face normal).
//!
//! Segment bounds are rigorous for any closed, consistently oriented mesh. Where the segment
//! stays in one triangle's face region ([`region`]), `f` is that triangle's plane distance; in an
//! edge's zone ([`edge`]) the edge's two triangles are the *candidates*, the only triangles that
//! can be closest there (a face region's piece that ends beside an edge goes on through its zone
//! in the same bound, [`TriangleMesh::through_zone`]); deep inside, those of the grid's cells
//! along the segment (the triangles within `|f(p)| + 2L` of its start `p`) where they are few;
//! elsewhere the bound is
//! the Lipschitz one of [`TriangleMesh::far_bound`]. Over candidates, every triangle's distance
//! `d_T` is convex along a line (the distance to a convex set), so it lies above its tangent at
//! the segment start and below its chord, and `|f| = min_T d_T`. While the lower bound
//! `A(s) = min_T tangent_T(s)` of `|f|` stays positive the sign cannot change, so the segment is
//! cut where it may cross the surface and each part gets linear bounds. The frame normal's range
//! follows from the candidates' vertex normals (or, for the gradient, from the monotone
//! derivatives of the `d_T`). A point query on the current segment searches the candidates only
//! (on a certified segment, its one triangle's projection).

mod bvh;
mod edge;
mod grid;
mod lines;
mod offset;
mod region;
mod triangle;

use super::{convex_bound, Aabb, Curvature, MeanSurface, SegmentBound, SegmentEnd, SurfacePoint};
use crate::error::{Error, ErrorKind, Result};
use crate::ordered::{less, more};
use bvh::Bvh;
use edge::EdgeZone;
use glam::{DVec2, DVec3};
use grid::CellGrid;
use region::FaceRegion;
use lines::{best_lower_line, closest_of, lower_lines, may_be_closest, positive_until, retain_flagged, Tangent};
use smallvec::SmallVec;
use std::collections::HashMap;
use triangle::{closer, closest_among, closest_on_triangle, segment_parameter, Attributes, Closest, Feature, Triangle};
use crate::frame::rescaled;

/// Per-candidate values of a segment bound, on the stack.
type Few<T> = SmallVec<[T; MAX_CANDIDATES]>;

/// The most candidate triangles a segment bound considers (each costs two closest-point
/// queries); with more, the far bound is used.
const MAX_CANDIDATES: usize = 16;
/// The bounds are padded by this many `epsilon` (rounding, and an undetermined sign right at
/// the start of a segment).
const PAD: f64 = 8.0;
/// A point query tries the certified regions of this many triangles of its cell's list (the
/// nearest to the cell's centre first) before searching the whole list, which finds the same
/// closest point: a region certified at the query point is nearly always among the first few,
/// and trying the rest cost more than it saved (of 2, 3, 4, 8 and all, 4 ran the fewest
/// instructions on the torus anchor, 1.6 % fewer than all).
const CERTIFIED_TRIES: usize = 4;
/// Certified pieces shorter than this fraction of the segment are left to the general bound.
const MIN_PIECE: f64 = 1e-3;
/// A certified piece shorter than this fraction of the tracker's tolerance (4σ: so σ) gives way
/// to the far bound over the whole segment when that is longer: an exact piece that ends a
/// fraction of σ further, at the next triangle's region, costs a segment for little distance,
/// where the Lipschitz bound of [`TriangleMesh::far_bound`] covers at least 3σ at a majorant
/// a few times looser. Against certified pieces of any length, the default scene (160×90,
/// 2 spp) rendered with 5.6 % fewer instructions at 1/4, 5.5 % at 1/2, 4.8 % at 1/8 and 3.7 %
/// at 1/16, its thick shells 4 % fewer and the thin torus anchor 0.15 %; the general bound in
/// its place saved nothing. So does a short piece in an edge's zone (0.4 % fewer).
const SHORT_PIECE: f64 = 0.25;
/// A certified piece that rises goes on through an edge's zone ([`TriangleMesh::through_zone`])
/// only where it ends at most this many tolerances above the surface: the tracker's tolerance is
/// 4σ and a default shell's top 3σ, beyond which a rising ray is leaving the shell. Of 0.25, 0.5,
/// 0.75, 1 and 1.5, 0.75 rendered the thin torus anchor with the fewest instructions (368.8,
/// 366.5, 364.7, 366.0 and 367.7 M).
const RISING_THROUGH_ZONE: f64 = 0.75;
/// Nor one that ends deeper than this many tolerances below the surface (4σ: σ): a free flight
/// from the top face of a default shell has collided before `f = −σ` with probability 0.84 at
/// normal incidence (more on slanted rays, whose optical depth per unit of `f` is larger), and the
/// zone's bound (~1.8k instructions) would mostly go unused; the few flights that go on start a
/// segment at the piece's end. Against going on at any depth, the thin torus anchor rendered
/// with 1.4 % fewer instructions at 1/4 (1.2 % at 0, 1.4 % at 1/8, 1.3 % at 3/8, 0.9 % at 1/2),
/// the default scene (160×90, 2 spp) with 0.1 % fewer.
const DEEP_THROUGH_ZONE: f64 = 0.25;
/// The far bound's reach beyond `|f|`, in tolerances (4σ: 3σ). Since the far bound took over
/// from the general one above and within the shell, against 1/2 (2σ), 3/4 rendered the
/// default scene (160×90, 2 spp) with 0.6 % fewer instructions and 1 with 0.7 % fewer; the
/// thin torus anchor the same.
const FAR_REACH: f64 = 0.75;
/// The grid's cells, in mean edge lengths.
const CELL_EDGES: f64 = 0.5;
/// The certified heights ([`region`]) and the grid's band ([`grid`]) stop at this many reaches
/// (the `reach` of [`TriangleMesh::new`]) from the mesh. The thin torus anchor (reach 3σ) renders
/// the same at 4 and at 8, and 0.4 % dearer at 2; at 4 its surface builds in 27 % fewer
/// instructions than at no limit (1,022 M to 743 M, mfrender's whole `--check` run).
const REACH_MULTIPLE: f64 = 4.0;

/// The two triangles of an edge whose zone holds a segment ([`edge`]), and how `f` bends there.
type ZonePair = ([u32; 2], Option<Curvature>);

/// A closed triangle mesh in world space; see the module documentation.
#[derive(Clone, Debug)]
pub struct TriangleMesh {
    /// In the hierarchy's leaf order, as are their attributes.
    triangles: Vec<Triangle>,
    attributes: Vec<Attributes>,
    bvh: Bvh,
    grid: CellGrid,
    /// Per triangle, where it is certainly the closest.
    regions: Vec<FaceRegion>,
    /// Per triangle and edge, where it or its neighbour across the edge is certainly closest.
    edges: Vec<[EdgeZone; 3]>,
    bounds: Aabb,
    /// Distances below this are rounding noise of the coordinates (1e-13 of the mesh's extent
    /// and offset, a hundred times their rounding): there the direction `p − c` is
    /// meaningless, and the bounds are padded by a multiple of it.
    epsilon: f64,
    /// Each triangle's corners as welded vertex ids (one per distinct position): the mesh's
    /// connectivity, for [`offset`].
    corners: Vec<[u32; 3]>,
    /// The threads its constructions may use (at least 1; the offset enclosures' too).
    threads: usize,
}

/// Candidate triangles of the current segment (see the module documentation).
#[derive(Clone, Debug, Default)]
pub struct MeshCache {
    candidates: grid::Lists,
    /// The current segment lies in the face region of its one candidate: a point query there
    /// is that triangle's projection ([`region::FaceRegion::face_closest`]).
    certified: bool,
    /// A point of the ray and the triangle closest to it (the start of the next segment); at NaN,
    /// a caller's hint ([`MeanSurface::seed_cache`]) that no query has confirmed yet.
    hint: Option<(DVec3, u32)>,
}

impl TriangleMesh {
    /// Builds the surface from world-space positions, triangles (vertex indices, counter-clockwise
    /// seen from outside), and optional per-vertex unit normals and texture coordinates, on up to
    /// `threads` threads (the calling one among them; 0 counts as 1), which its offset enclosures
    /// use too. The surface is the same whatever the thread count.
    ///
    /// `reach` (positive; `f64::INFINITY` for no limit) is the largest distance from the mesh at
    /// which media will be tracked on it: a macrofacet medium's shell top `kσ` (seeds/000
    /// Sec. 4). The closed forms that make a thin shell's bounds cheap (certified face heights,
    /// the grid's band) are built up to [`REACH_MULTIPLE`] reaches from the mesh, so a thin
    /// shell's surface builds faster; beyond, queries search. Distances, gradients and frames are
    /// the same whatever the reach (up to rounding); a tracking call's segments may split
    /// differently, so that with one seed it may draw different, equally distributed, events.
    pub fn new(positions: &[DVec3], indices: &[[u32; 3]], normals: Option<&[DVec3]>, uvs: Option<&[DVec2]>, threads: usize, reach: f64) -> Result<TriangleMesh> {
        let invalid = |m: String| Error::new(ErrorKind::InvalidArgument, m);
        if !(reach > 0.0) {
            return Err(invalid(format!("the reach must be positive (infinity for no limit), got {reach}")));
        }
        if indices.is_empty() {
            return Err(invalid("the mesh has no triangles".into()));
        }
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(invalid(format!("vertex {i} is not finite: {}", positions[i])));
        }
        // Lengths beyond the sigma range make the acceleration grid's volume and the
        // closest-point arithmetic overflow (found by fuzzing: a tetrahedron 1e103 wide panicked,
        // one 1e77 wide answered the wrong f).
        let limit = crate::limits::SIGMA_RANGE.1;
        if let Some(i) = positions.iter().position(|p| p.abs().max_element() > limit) {
            return Err(invalid(format!("vertex {i} = {} lies beyond ±{limit:e}, the range of lengths the library supports", positions[i])));
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
        // Below the sigma range the grid's cells and the rounding scale underflow (found by
        // fuzzing: a mesh 2.9e-320 wide overflowed the grid's cell count).
        let (lo, hi) = indices.iter().flatten().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &v| (lo.min(positions[v as usize]), hi.max(positions[v as usize])));
        let (extent, smallest) = ((hi - lo).max_element(), crate::limits::SIGMA_RANGE.0);
        if !(extent >= smallest) {
            return Err(invalid(format!("the mesh spans {extent:e}, below the smallest length the library supports ({smallest:e})")));
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

        // The edges rescaled before their cross product, and it before normalising: edges of
        // 1.7e-161 have a subnormal cross product, whose normal came out of length 1.00007
        // (found by fuzzing).
        let face_normal = |tri: &[u32; 3]| {
            let [a, b, c] = tri.map(|v| positions[v as usize]);
            rescaled(rescaled(b - a).cross(rescaled(c - a))).try_normalize().unwrap_or(DVec3::ZERO)
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

        // A medium fills the mesh's interior: the mesh must be closed (every edge shared by an
        // even number of triangles; zero-area triangles count like any other).
        // Per edge, its uses and their balance (+1 from the lower vertex id, −1 back).
        let mut edge_uses: HashMap<(u32, u32), (u32, i32)> = HashMap::new();
        for tri in indices {
            let w = corners(tri);
            for i in 0..3 {
                let (u, v) = (w[i], w[(i + 1) % 3]);
                if u != v {
                    let uses = edge_uses.entry((u.min(v), u.max(v))).or_insert((0, 0));
                    *uses = (uses.0 + 1, uses.1 + if u < v { 1 } else { -1 });
                }
            }
        }
        let open = edge_uses.values().filter(|(n, _)| n % 2 == 1).count();
        if open > 0 {
            return Err(invalid(format!("the mesh is not closed: {open} edges belong to an odd number of triangles (a mean surface must enclose its interior)")));
        }
        // Consistent winding: each edge crossed as often in one direction as in the other (found
        // by fuzzing: a triangle given twice with the same winding passed as closed, and a
        // closest-point query on it found no triangle, a panic).
        let unpaired = edge_uses.values().filter(|(_, balance)| *balance != 0).count();
        if unpaired > 0 {
            return Err(invalid(format!("the mesh's winding is inconsistent: {unpaired} edges are crossed more often in one direction than in the other (neighbouring triangles must wind the same way, counter-clockwise seen from outside)")));
        }
        // The winding says which side is inside: counter-clockwise seen from outside encloses a
        // positive volume. Turned inside out, f < 0 would fill the space around the mesh up to its
        // bounding box, where f turns positive (found by fuzzing: an octahedron scaled by −3 had
        // enclosure vertices inside the region). In units of the extent, about the box's centre,
        // beyond the rounding of a flat mesh's zero volume.
        let centre = 0.5 * (lo + hi);
        let volume: f64 = indices
            .iter()
            .map(|tri| {
                let [a, b, c] = tri.map(|v| (positions[v as usize] - centre) / extent);
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        if volume < -1e-12 {
            return Err(invalid(format!("the mesh is inside out: its triangles wind clockwise seen from outside (signed volume {:e}); reverse each triangle's winding", volume * extent.powi(3))));
        }

        let (triangles, attributes): (Vec<Triangle>, Vec<Attributes>) = indices
            .iter()
            .map(|tri| {
                let p = tri.map(|v| positions[v as usize]);
                let n = face_normal(tri);
                let w = corners(tri);
                // Rescaled first: opposite face normals sum to ~1e-160, whose squared length is
                // subnormal (found by fuzzing: an edge pseudo-normal of length 1.0000167).
                let pn = |v: DVec3| rescaled(v).try_normalize().unwrap_or(n);
                let edge = |i: usize| {
                    let (u, v) = (w[i], w[(i + 1) % 3]);
                    pn(edge_pn.get(&(u.min(v), u.max(v))).copied().unwrap_or(DVec3::ZERO))
                };
                let shading = normals.map(|ns| tri.map(|v| rescaled(ns[v as usize]).normalize()));
                let shading_min_length = shading.map_or(0.0, |ns| {
                    // |Σ b_i n_i| >= (Σ b_i n_i)·u >= min_i n_i·u for the unit mean direction u.
                    let u = (ns[0] + ns[1] + ns[2]).try_normalize().unwrap_or(DVec3::ZERO);
                    ns.iter().map(|n| n.dot(u)).fold(f64::INFINITY, f64::min).max(0.0)
                });
                let geometry = Triangle::new(p, n);
                let attributes = Attributes {
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
                    uv: uvs.map(|uv| tri.map(|v| uv[v as usize])),
                };
                (geometry, attributes)
            })
            .unzip();

        let mean_edge = indices
            .iter()
            .map(|t| (positions[t[1] as usize] - positions[t[0] as usize]).length() + (positions[t[2] as usize] - positions[t[1] as usize]).length() + (positions[t[0] as usize] - positions[t[2] as usize]).length())
            .sum::<f64>()
            / (3 * indices.len()) as f64;
        let (bvh, order) = Bvh::build(&triangles);
        let triangles: Vec<Triangle> = order.iter().map(|&i| triangles[i as usize].clone()).collect();
        let attributes: Vec<Attributes> = order.iter().map(|&i| attributes[i as usize].clone()).collect();
        let (min, max) = bvh.bounds();
        let threads = threads.max(1);
        let covered = REACH_MULTIPLE * reach;
        let grid = CellGrid::build(&bvh, &triangles, min, max, CELL_EDGES * mean_edge, covered, threads);
        let bounds = Aabb { min, max };
        let epsilon = 1e-13 * (bounds.max - bounds.min).max_element().max(bounds.max.abs().max(bounds.min.abs()).max_element()).max(1e-300);
        let regions = FaceRegion::build(&bvh, &triangles, epsilon, covered, threads);
        let welded_corners: Vec<[u32; 3]> = order.iter().map(|&i| corners(&indices[i as usize])).collect();
        let edges = EdgeZone::build(&bvh, &triangles, &welded_corners, epsilon, threads);
        Ok(TriangleMesh { triangles, attributes, bvh, grid, regions, edges, bounds, epsilon, corners: welded_corners, threads })
    }

    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The closest point of the whole mesh to `p`: from the grid's list near the surface, else
    /// by the hierarchy.
    /// Most queries of a thin shell are settled by the certified region ([`region`]) of one
    /// triangle of the cell's list, a test much cheaper than a closest point.
    /// `hint`: a triangle closest to a point nearby (e.g. the previous one along a ray), tried
    /// first, and outside the grid the seed of the hierarchy's search.
    fn closest(&self, p: DVec3, hint: Option<u32>) -> Closest {
        let certified = |i: u32| self.regions[i as usize].certified_closest(self.triangles[i as usize].n, p, i);
        if let Some(found) = hint.and_then(certified) {
            return found;
        }
        let mut seed = Closest::NONE;
        if let Some(list) = self.grid.list_at(p) {
            if let Some(found) = list.iter().take(CERTIFIED_TRIES).find_map(|&i| certified(i)) {
                return found;
            }
            seed = closest_among(&self.triangles, p, list, Closest::NONE);
            // A cell's list without a number among its distances falls through to the whole
            // mesh (found by fuzzing: sliver triangles 5e-37 wide and 40 long, a panic), and so
            // does a point farther than the lists cover (a mesh built for a reach), from there.
            let covered = self.grid.covered();
            if seed.triangle != Closest::NONE.triangle && seed.distance_sq <= covered * covered {
                return seed;
            }
        }
        if seed.triangle == Closest::NONE.triangle {
            seed = hint.map_or(Closest::NONE, |i| closest_on_triangle(&self.triangles[i as usize], p, i));
        }
        let found = self.bvh.closest(&self.triangles, p, seed);
        if found.triangle == Closest::NONE.triangle {
            self.closest_far(p)
        } else {
            found
        }
    }

    /// The closest point to a `p` so far away that the products of the closest-point test
    /// overflow (every distance NaN; found by fuzzing: 1e300 from a mesh 3e49 wide gave no
    /// triangle, a panic): the test in coordinates scaled by a power of two, over every triangle,
    /// the distance then scaled back (`+∞` when it overflows).
    fn closest_far(&self, p: DVec3) -> Closest {
        let largest = p.abs().max_element().max(self.bounds.min.abs().max_element()).max(self.bounds.max.abs().max_element());
        let scale = 2f64.powi(-(largest.log2().ceil() as i32).clamp(-1022, 1023));
        let mut best = Closest::NONE;
        for (i, t) in self.triangles.iter().enumerate() {
            let scaled = Triangle { p: t.p.map(|v| v * scale), ..t.clone() };
            let c = closest_on_triangle(&scaled, p * scale, i as u32);
            if closer(&c, &best) {
                best = c;
            }
        }
        if best.triangle == Closest::NONE.triangle {
            // No number among the distances: the mesh is below the rounding of p's coordinates
            // (scaled, its edges were subnormal; found by fuzzing: an octahedron 4 wide seen from
            // 1.8e308, a panic), or its triangles are slivers. The nearest vertex stands for it.
            // (In scaled coordinates, as `best` is.)
            let vertex = |i: usize, k: usize| {
                let v = self.triangles[i].p[k] * scale;
                Closest { triangle: i as u32, point: v, barycentric: [DVec3::X, DVec3::Y, DVec3::Z][k], feature: Feature::Vertex(k), distance_sq: (p * scale - v).length_squared() }
            };
            best = (0..self.triangles.len()).flat_map(|i| (0..3).map(move |k| (i, k))).map(|(i, k)| vertex(i, k)).min_by(|a, b| a.distance_sq.total_cmp(&b.distance_sq)).expect("a mesh has triangles");
        }
        Closest { point: best.point / scale, distance_sq: best.distance_sq / (scale * scale), ..best }
    }

    /// The triangle recorded in `cache` as closest to a point of the current ray.
    fn recorded(cache: &MeshCache) -> Option<u32> {
        cache.hint.map(|(_, i)| i)
    }

    /// The triangle recorded in `cache` as closest at exactly `p` (every query and bound records
    /// the closest one).
    fn hint_at(cache: &MeshCache, p: DVec3) -> Option<u32> {
        cache.hint.filter(|(q, _)| *q == p).map(|(_, i)| i)
    }

    /// The sign of `f` at `p`, whose closest point is `c`, by the pseudo-normal of `c`'s feature
    /// (returned too).
    #[inline]
    fn side(&self, p: DVec3, c: &Closest) -> (f64, DVec3) {
        let tri = &self.attributes[c.triangle as usize];
        let pseudo = match c.feature {
            Feature::Face => self.triangles[c.triangle as usize].n,
            Feature::Edge(i) => tri.edge_pn[i],
            Feature::Vertex(i) => tri.vertex_pn[i],
        };
        // Outside the bounding box is outside the (closed) mesh. Far away the pseudo-normal test
        // is no help: every feature is at the same rounded distance (found by fuzzing: a point
        // 1.5e47 from a tetrahedron 2000 wide got f < 0).
        let outside_box = p.cmplt(self.bounds.min).any() || p.cmpgt(self.bounds.max).any();
        (if outside_box || (p - c.point).dot(pseudo) >= 0.0 { 1.0 } else { -1.0 }, pseudo)
    }

    /// `f` at `p`, whose closest point is `c`: [`Self::surface_point`]'s, without the frame.
    fn signed_distance(&self, p: DVec3, c: &Closest) -> f64 {
        self.side(p, c).0 * c.distance_sq.sqrt()
    }

    /// The surface point of a closest-point result.
    fn surface_point(&self, p: DVec3, c: &Closest) -> SurfacePoint {
        let tri = &self.attributes[c.triangle as usize];
        let (sign, pseudo) = self.side(p, c);
        let offset = p - c.point;
        let distance = c.distance_sq.sqrt();
        let normal = match (tri.shading, c.feature) {
            (Some(ns), _) => (c.barycentric.x * ns[0] + c.barycentric.y * ns[1] + c.barycentric.z * ns[2]).try_normalize().unwrap_or(pseudo),
            // ∇(±|p − c|) over a face is its normal on both sides, exactly.
            (None, Feature::Face) => pseudo,
            // The offset normalised, rescaled first (not offset / distance: the closest-point
            // test's distance is rounded apart from |offset|, and |offset|² of a tiny mesh is
            // subnormal).
            (None, _) if distance > self.epsilon => sign * rescaled(offset).try_normalize().unwrap_or(pseudo),
            (None, _) => pseudo,
        };
        // Mitsuba's uv: the texture coordinates interpolated at the closest point, else the
        // barycentric coordinates of corners 1 and 2.
        let b = c.barycentric;
        let uv = match tri.uv {
            Some(uv) => b.x * uv[0] + b.y * uv[1] + b.z * uv[2],
            None => DVec2::new(b.y, b.z),
        };
        SurfacePoint { f: sign * distance, normal, tangent: tri.dpdu, uv }
    }

    /// The range of `d·n` over the interpolated vertex normals `n = m/|m|`, `m = Σ b_i n_i`,
    /// at the closest points on triangle `i` of a segment of `length` whose start projects to
    /// barycentric `b0`; `None` without vertex normals (the frame is the distance gradient).
    /// The closest-point map is 1-Lipschitz, so those points lie within `length` of the first,
    /// where `m` changes by at most `shading_lipschitz × length`; the triangle's vertex normals
    /// bound it too.
    fn shading_cos_range(&self, i: u32, d: DVec3, b0: DVec3, length: f64) -> Option<[f64; 2]> {
        let tri = &self.attributes[i as usize];
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

impl TriangleMesh {
    /// `d_T(q)` and `d/ds d_T(q + s d)` for every candidate `T`. At distance 0 the triangle's
    /// plane gives the slope of a supporting line of the convex `d_T`.
    ///
    /// The derivative is the direction `(q − c)/|q − c|`, whose rounding error (about
    /// `1e-15 × coordinates / distance`) would tilt the tangent by more than `epsilon` over a
    /// segment of `length` when the distance is below `2e-3 length`: there the derivative is
    /// marked unreliable (the tangent is replaced by the Lipschitz line, the gradient's range by
    /// `[-1, 1]`).
    fn tangents(&self, q: DVec3, d: DVec3, candidates: &[u32], length: f64) -> Few<Tangent> {
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

impl TriangleMesh {
    /// The bound without candidate triangles, over at most `max(|f(p)|, FAR_REACH × tolerance)`:
    /// within `|f(p)|` of the start the sign of `f` cannot change, so one side is the chord of
    /// the distance to the triangle closest at the start (`|f| <= d_T`, convex) and the other the
    /// Lipschitz line; beyond, both are Lipschitz lines. Any frame normal.
    fn far_bound(&self, start: &SurfacePoint, p: DVec3, d: DVec3, length: f64, tolerance: f64, cache: &MeshCache) -> SegmentBound {
        let reach = start.f.abs() * (1.0 - 1e-12);
        let length = length.min(reach.max(FAR_REACH * tolerance)).max(f64::MIN_POSITIVE);
        let mut bound = SegmentBound::lipschitz(start.f, length, self.lipschitz());
        if length <= reach {
            // The triangle closest at the start, when the cache recorded it there.
            let nearest = Self::hint_at(cache, p).unwrap_or_else(|| self.closest(p, Self::recorded(cache)).triangle);
            let end = closest_on_triangle(&self.triangles[nearest as usize], p + length * d, nearest);
            let chord = [start.f.abs() + PAD * self.epsilon, end.distance_sq.sqrt() + PAD * self.epsilon];
            if start.f > 0.0 {
                bound.f_hi = chord;
            } else {
                bound.f_lo = [-chord[0], -chord[1]];
            }
        }
        bound
    }
}

impl TriangleMesh {
    /// The common case of a thin shell, in O(1): a piece of the segment inside the certified
    /// region of one triangle `T` ([`region`]), where `f` is exactly the signed distance to `T`'s
    /// plane and the frame normal is `T`'s interpolated vertex normal (affine along the piece)
    /// or its face normal, of the triangle closest at `p` (the one recorded there, else a query);
    /// a piece cut short where the ray leaves the region beside an edge goes on through that
    /// edge's zone in the same bound ([`Self::through_zone`]). Otherwise `Err` with the length
    /// the general bound should cover: where `p` is about to cross the strip beside an edge that
    /// no triangle certifies (a ray passing from one triangle's region into its neighbour's),
    /// only that strip, whose few candidates make the general bound cheap; else the whole
    /// `length`. Or, where that begins in an edge's zone ([`edge`]), its piece in the zone with
    /// the edge's two triangles, the only candidates there. `tolerance` is the tracker's
    /// ([`MeanSurface::bound`]).
    fn certified_bound(&self, p: DVec3, d: DVec3, length: f64, tolerance: f64, cache: &mut MeshCache) -> std::result::Result<SegmentBound, (f64, Option<ZonePair>)> {
        // A triangle recorded at `p` is the closest there (every query and bound records the
        // closest): asking again would find it, or one as close, again.
        let i = Self::hint_at(cache, p).unwrap_or_else(|| self.closest(p, Self::recorded(cache)).triangle);
        let region = &self.regions[i as usize];
        let tri = &self.triangles[i as usize];
        let piece = region.piece(tri.n, p, d, length).map_or(0.0, |piece| piece.length);
        // A sliver (the start on the region's boundary, up to rounding) would not advance.
        if piece < MIN_PIECE * length {
            // (Not below MIN_PIECE of the segment: a sliver triangle's strip may lie below the
            // rounding of the ray's distance.)
            let general = region.strip_crossing(p, d).map_or(length, |strip| length.min(strip.max(MIN_PIECE * length)));
            // The longest piece of it in an edge's zone, if any: there the edge's two triangles
            // are the only candidates.
            let best = self.zone_piece(i, p, d, general);
            return Err(best.map_or((general, None), |(piece, zone)| (piece, Some(([i, zone.neighbour], zone.curvature)))));
        }
        let end_p = p + piece * d;
        let (start, end) = (region.face_closest(tri.n, p, i), region.face_closest(tri.n, end_p, i));
        let plane = [tri.n.dot(p - tri.p[0]), tri.n.dot(end_p - tri.p[0])];
        let pad = PAD * self.epsilon;
        let attributes = &self.attributes[i as usize];
        let cos = match attributes.shading {
            None => [d.dot(tri.n); 2],
            Some(ns) => {
                // m(s) = Σ b_i(s) n_i is affine along the piece; |m| is convex, so its minimum
                // over the piece is at an end or at the foot of the perpendicular.
                let m = |b: DVec3| b.x * ns[0] + b.y * ns[1] + b.z * ns[2];
                let (m0, m1) = (m(start.barycentric), m(end.barycentric));
                let dm = m1 - m0;
                let foot = segment_parameter(DVec3::ZERO, m0, m1);
                let min_len = more((m0 + foot * dm).length(), attributes.shading_min_length);
                if !(min_len > 0.0) {
                    return Err((length, None));
                }
                let (a, b) = (less(d.dot(m0), d.dot(m1)), more(d.dot(m0), d.dot(m1)));
                // d·m lies in [a, b]; dividing by |m| ∈ [min_len, 1] can magnify it up to 1/min_len.
                [if a < 0.0 { a / min_len } else { a }, if b > 0.0 { b / min_len } else { b }]
            }
        };
        // (In a certified piece of a validated ray nothing is NaN: minima by comparison.)
        let bound = SegmentBound {
            length: piece,
            f_lo: [plane[0] - pad, plane[1] - pad],
            f_hi: [plane[0] + pad, plane[1] + pad],
            cos: [more(cos[0] - 1e-12, -1.0), less(cos[1] + 1e-12, 1.0)],
            // The frame there only if a segment starts there (MeanSurface::end_point).
            end: SegmentEnd::Height(self.signed_distance(end_p, &end)),
        };
        cache.candidates.clear();
        // (Not for a piece that rises beyond RISING_THROUGH_ZONE of the tolerance: the ray is
        // then mostly leaving the shell, and the tracker would not use the rest. Nor for one
        // that ends below DEEP_THROUGH_ZONE of it: a flight has then mostly collided.)
        if piece < length && (plane[1] <= RISING_THROUGH_ZONE * tolerance || tri.n.dot(d) <= 0.0) && !(plane[1] < -DEEP_THROUGH_ZONE * tolerance) {
            if let Some((merged, pair, end_closest)) = self.through_zone(i, p, d, length, &bound, &end) {
                cache.candidates.extend_from_slice(&pair);
                cache.certified = false;
                cache.hint = Some((p + merged.length * d, end_closest.triangle));
                return Ok(merged);
            }
        }
        cache.candidates.push(i);
        cache.certified = true;
        cache.hint = Some((end_p, i));
        Ok(bound)
    }

    /// The longest piece of the segment `p + s d`, `s ∈ [0, length]`, in a zone of triangle
    /// `i`'s edges ([`edge`]), with its zone.
    fn zone_piece(&self, i: u32, p: DVec3, d: DVec3, length: f64) -> Option<(f64, &EdgeZone)> {
        let mut best: Option<(f64, &EdgeZone)> = None;
        for k in 0..3 {
            if let Some((piece, zone)) = self.edge_zone_piece(i, k, p, d, length) {
                if best.map_or(true, |(b, _)| piece > b) {
                    best = Some((piece, zone));
                }
            }
        }
        best
    }

    /// [`Self::zone_piece`] in the zone of edge `k` alone.
    fn edge_zone_piece(&self, i: u32, k: usize, p: DVec3, d: DVec3, length: f64) -> Option<(f64, &EdgeZone)> {
        let zone = &self.edges[i as usize][k];
        // Only a zone whose edge's line lies within its widest radius of `p` can hold it
        // (`|e_k|` bounds the distance to that line from below): the other zones' tests cost a
        // thin shell's crossings more than their bounds.
        if zone.neighbour == u32::MAX || !(self.regions[i as usize].edge_distance(k, p).abs() <= zone.widest() * (1.0 + 1e-9) + self.epsilon) {
            return None;
        }
        Some((zone.piece(&self.triangles[i as usize], k, p, d, length, MIN_PIECE * length)?, zone))
    }

    /// A certified piece of triangle `i` from `p` (`piece`, shorter than the `length` asked
    /// for) continued in the same segment through the zone of an edge that holds its end
    /// ([`edge`]): there `f` is bounded by [`Self::dihedral_bound`], on the piece it is the
    /// plane's exact line. One line below both (above both) bounds `f` on the whole segment
    /// where it lies below (above) each at the ends of each part, the lines being straight on
    /// each: the line from the piece's start to the zone part's end, moved down (up) by what
    /// it lacks where the parts meet. (At a convex edge the plane's line is the dihedral's lower
    /// tangent there, at a concave one its upper: that line does not move.) Saves the tracker a
    /// segment and the zone's search for where it starts: a thin shell's crossing of an edge
    /// cost three segments (the piece, the zone, the next triangle's piece). `piece_end` is the
    /// closest point at the piece's end. Returns the bound, the zone's two triangles and the
    /// closest point at the end; `None` where no zone holds the piece's end or the dihedral
    /// bound does not apply there.
    fn through_zone(&self, i: u32, p: DVec3, d: DVec3, length: f64, piece: &SegmentBound, piece_end: &Closest) -> Option<(SegmentBound, [u32; 2], Closest)> {
        let s1 = piece.length;
        let q1 = p + s1 * d;
        // The piece ended where the ray left the region across its nearest edge (or at its
        // height, where the nearest edge's zone may still hold it).
        let e = self.regions[i as usize].edge_distances(q1);
        let nearest = if e[0] <= e[1] && e[0] <= e[2] { 0 } else if e[1] <= e[2] { 1 } else { 2 };
        let (zone_length, zone) = self.edge_zone_piece(i, nearest, q1, d, length - s1)?;
        let pair = [i, zone.neighbour];
        // (Rounded, the sum may pass the length asked for by an ulp.)
        let s2 = less(s1 + zone_length, length);
        let end_p = p + s2 * d;
        let end_closest = closest_among(&self.triangles, end_p, &pair, Closest::NONE);
        let end = self.surface_point(end_p, &end_closest);
        // (At `q1` the piece's triangle is closest, at its projection.)
        let at_start = [*piece_end, closest_on_triangle(&self.triangles[pair[1] as usize], q1, pair[1])];
        let zone_bound = self.dihedral_bound(&self.surface_point(q1, piece_end), &at_start, &end, &end_closest, q1, d, zone_length, pair, zone.curvature?)?;
        // The lines at the parts' meeting point `s1`, and the straight line from the start to
        // the end: how far it lies above the lower bounds there (below the upper).
        let at_s1 = |ends: [f64; 2]| ends[0] + (ends[1] - ends[0]) * (s1 / s2);
        let f_lo = [piece.f_lo[0], zone_bound.f_lo[1]];
        let f_hi = [piece.f_hi[0], zone_bound.f_hi[1]];
        let lower_by = (at_s1(f_lo) - less(piece.f_lo[1], zone_bound.f_lo[0])).max(0.0);
        let raise_by = (more(piece.f_hi[1], zone_bound.f_hi[0]) - at_s1(f_hi)).max(0.0);
        let merged = SegmentBound {
            length: s2,
            f_lo: f_lo.map(|f| f - lower_by),
            f_hi: f_hi.map(|f| f + raise_by),
            cos: [less(piece.cos[0], zone_bound.cos[0]), more(piece.cos[1], zone_bound.cos[1])],
            end: SegmentEnd::Point(end),
        };
        Some((merged, pair, end_closest))
    }
}

impl TriangleMesh {
    /// The bound in an edge's zone ([`edge`]) from the two ends alone: there `f` is the signed
    /// distance to the dihedral of the edge's two triangles, convex or concave along every line,
    /// so [`convex_bound`] over its gradients at the ends bounds it. The frame normal's range is
    /// that of the gradient or, with vertex normals, of both triangles' interpolated normals (as
    /// in the general bound). `None` where an end lies so near the surface that its gradient's
    /// direction is rounding (as the general bound's tangents), and the general bound decides.
    /// `at_start` are the closest points of the two triangles to `p`, `end` is the surface point
    /// at the end, `end_closest` its closest point.
    #[allow(clippy::too_many_arguments)]
    fn dihedral_bound(&self, start: &SurfacePoint, at_start: &[Closest; 2], end: &SurfacePoint, end_closest: &Closest, p: DVec3, d: DVec3, length: f64, pair: [u32; 2], curvature: Curvature) -> Option<SegmentBound> {
        let floor = start.f.abs().min(end.f.abs());
        if !(floor >= 2e-3 * length && floor > self.epsilon) {
            return None;
        }
        // ∇f: over a face its normal (on both sides), elsewhere ±(q − c)/|q − c|.
        let gradient = |q: DVec3, f: f64, c: &Closest| match c.feature {
            Feature::Face => Some(self.triangles[c.triangle as usize].n),
            _ => rescaled(q - c.point).try_normalize().map(|n| f.signum() * n),
        };
        let start_closest = if closer(&at_start[1], &at_start[0]) { at_start[1] } else { at_start[0] };
        let (g0, g1) = (gradient(p, start.f, &start_closest)?, gradient(p + length * d, end.f, end_closest)?);
        let bound = convex_bound(&SurfacePoint { normal: g0, ..*start }, &SurfacePoint { normal: g1, ..*end }, d, length, curvature);
        let cos = if self.attributes[pair[0] as usize].shading.is_some() {
            let ranges = [0, 1].map(|k| self.shading_cos_range(pair[k], d, at_start[k].barycentric, length));
            let [Some(a), Some(b)] = ranges else { return None };
            [a[0].min(b[0]), a[1].max(b[1])]
        } else {
            // The ends' gradients (q − c)/|q − c| are rounded by up to ~4ε × coordinates /
            // distance (a face's normal is exact; the widening covers both).
            let coordinates = p.abs().max((p + length * d).abs()).max_element();
            let rounding = 4.0 * f64::EPSILON * coordinates / floor;
            [bound.cos[0] - rounding, bound.cos[1] + rounding]
        };
        let pad = PAD * self.epsilon;
        Some(SegmentBound {
            length,
            f_lo: bound.f_lo.map(|f| f - pad),
            f_hi: bound.f_hi.map(|f| f + pad),
            cos: [(cos[0] - 1e-12).max(-1.0), (cos[1] + 1e-12).min(1.0)],
            end: SegmentEnd::Point(*end),
        })
    }
}

impl MeanSurface for TriangleMesh {
    type Cache = MeshCache;

    fn point(&self, p: DVec3) -> Result<SurfacePoint> {
        Ok(self.surface_point(p, &self.closest(p, None)))
    }

    fn start_point(&self, p: DVec3, cache: &mut MeshCache) -> Result<SurfacePoint> {
        let closest = self.closest(p, Self::recorded(cache));
        cache.hint = Some((p, closest.triangle));
        Ok(self.surface_point(p, &closest))
    }

    fn hint(&self, cache: &MeshCache) -> u64 {
        // The triangle last found closest to a point of the ray: on a certified segment its one
        // candidate (`certified_bound` records it), elsewhere near.
        Self::recorded(cache).map_or(0, |i| u64::from(i) + 1)
    }

    fn seed_cache(&self, cache: &mut MeshCache, hint: u64) {
        // Recorded at no point (NaN): `hint_at` trusts only triangles a query found closest.
        if let Some(i) = hint.checked_sub(1).filter(|&i| i < self.triangles.len() as u64) {
            cache.hint = Some((DVec3::NAN, i as u32));
        }
    }

    fn end_point(&self, p: DVec3, cache: &mut MeshCache) -> Result<SurfacePoint> {
        // The end of a certified piece (`certified_bound`, which recorded its triangle there):
        // a point of its segment, its projection, as the bound's end height was computed.
        if cache.certified && Self::hint_at(cache, p).is_some() {
            return self.point_on_segment(p, cache);
        }
        self.start_point(p, cache)
    }

    fn point_on_segment(&self, p: DVec3, cache: &MeshCache) -> Result<SurfacePoint> {
        if cache.certified {
            let i = cache.candidates[0];
            return Ok(self.surface_point(p, &self.regions[i as usize].face_closest(self.triangles[i as usize].n, p, i)));
        }
        let found = if cache.candidates.is_empty() { Closest::NONE } else { closest_among(&self.triangles, p, &cache.candidates, Closest::NONE) };
        if found.triangle == Closest::NONE.triangle {
            // A query of the whole mesh, from the triangle closest to a point of this ray.
            return Ok(self.surface_point(p, &self.closest(p, Self::recorded(cache))));
        }
        Ok(self.surface_point(p, &found))
    }

    fn bound(&self, start: &SurfacePoint, p: DVec3, d: DVec3, length: f64, tolerance: f64, cache: &mut MeshCache) -> Result<SegmentBound> {
        let (short, requested) = (SHORT_PIECE * tolerance, length);
        cache.certified = false;
        // The far bound over the length asked for, with no candidates for the point queries.
        let far = |cache: &mut MeshCache| {
            cache.candidates.clear();
            Ok(self.far_bound(start, p, d, requested, tolerance, cache))
        };
        let (length, pair) = match self.certified_bound(p, d, length, tolerance, cache) {
            Ok(bound) if bound.length < short && requested > short => {
                // The certified piece's triangle is the closest at `p`: the far bound's chord
                // starts from it. (Its end and candidate were recorded for a segment not taken.)
                cache.hint = Some((p, cache.candidates[0]));
                cache.certified = false;
                return far(cache);
            }
            Ok(bound) => return Ok(bound),
            Err(general) => general,
        };
        // A short piece in an edge's zone, as a short certified one.
        if pair.is_some() && length < short && requested > short {
            return far(cache);
        }
        let end_p = p + length * d;
        let (end_closest, f_end, tent);
        if let Some((pair, curvature)) = pair {
            // An edge's zone: one of its two triangles is the closest everywhere on the segment.
            cache.candidates.clear();
            cache.candidates.extend_from_slice(&pair);
            end_closest = closest_among(&self.triangles, end_p, &pair, Closest::NONE);
            let end = self.surface_point(end_p, &end_closest);
            let at_start = pair.map(|i| closest_on_triangle(&self.triangles[i as usize], p, i));
            if let Some(bound) = curvature.and_then(|c| self.dihedral_bound(start, &at_start, &end, &end_closest, p, d, length, pair, c)) {
                cache.hint = Some((end_p, end_closest.triangle));
                return Ok(bound);
            }
            f_end = end.f;
            tent = (start.f.abs(), f_end.abs());
        } else {
            // Deep inside (below −tolerance), the candidates: the union of the grid's lists along
            // the segment, less the triangles that cannot be closest anywhere on it (the closest
            // triangle to q(s) lies within |f(q(s))| <= tent(s) = min(|f(p)| + s, |f(end)| +
            // L − s) of it, f being 1-Lipschitz). There the density is large and the far bound,
            // long (|f|) and for any normal, would take tentative collisions without end where
            // the candidates' normals see no flake (`fuzz_regressions_tracking`: deep inside an
            // octahedron). Elsewhere, outside the grid's band or with many candidates, the far
            // bound over the length asked for: above and within the shell, the general bound
            // cost more than the segments and tentative collisions it saved (the default scene
            // at 160×90, 2 spp rendered with 9.1 % fewer instructions without it, the thin torus
            // anchor with 1.8 % fewer).
            // (The grid's lists hold the closest triangles of the segment's points within its
            // covered distance of the mesh: all of them are within |f(p)| + length.)
            if !(start.f < -tolerance && -start.f + length <= self.grid.covered() && self.grid.segment(p, d, length, &mut cache.candidates)) {
                return far(cache);
            }
            end_closest = self.closest(end_p, Self::recorded(cache));
            f_end = self.surface_point(end_p, &end_closest).f;
            tent = (start.f.abs(), f_end.abs());
            // Drop the triangles whose bounding sphere stays beyond the tent from the segment.
            let reach = 0.5 * (tent.0 + tent.1 + length) * (1.0 + 1e-9) + self.epsilon;
            cache.candidates.retain(|i| {
                let t = &self.triangles[*i as usize];
                let along = (t.centre - p).dot(d).clamp(0.0, length);
                (t.centre - (p + along * d)).length() - t.radius <= reach
            });
            if cache.candidates.len() > MAX_CANDIDATES {
                return far(cache);
            }
            if !cache.candidates.contains(&end_closest.triangle) {
                cache.candidates.push(end_closest.triangle); // guards against rounding
            }
        }
        let first = self.tangents(p, d, &cache.candidates, length);
        let last = self.tangents(p + length * d, d, &cache.candidates, length);
        let mut keep: Few<bool> = first.iter().zip(&last).map(|(a, b)| may_be_closest(a, b, tent, length, self.epsilon)).collect();
        // The closest triangle at the end always qualifies (this guards against rounding).
        if let Some(k) = cache.candidates.iter().position(|&i| i == end_closest.triangle) {
            keep[k] = true;
        }
        retain_flagged(&mut cache.candidates, &keep);
        let (mut first, mut last) = (first, last);
        retain_flagged(&mut first, &keep);
        retain_flagged(&mut last, &keep);

        // Lower lines of |f(p + s d)| = min_T d_T: per candidate lines below d_T, lowered by the
        // coordinates' rounding (about `epsilon`). The sign of f can only change where every
        // line of some candidate is <= 0.
        let eps = self.epsilon;
        let start_lines: Few<[(f64, f64); 3]> = first.iter().map(|t| lower_lines(t, 0.0, eps)).collect();
        let end_lines: Few<[(f64, f64); 3]> = last.iter().map(|t| lower_lines(t, length, eps)).collect();
        // Within |f(p)| of the start the sign cannot change either (f is 1-Lipschitz).
        let lipschitz_reach = start.f.abs() * (1.0 - 1e-12);
        // A cut shorter than this is not worth a segment of its own.
        let min_piece = 1e-6 * length;
        let (piece, sign) = if let Some(first_zero) = positive_until(&start_lines) {
            (first_zero.max(lipschitz_reach).min(length), start.f.signum())
        } else {
            // Mirrored: from the end, the sign is that of f(L) after the last zero.
            let mirrored: Few<[(f64, f64); 3]> = end_lines.iter().map(|ls| ls.map(|(v, k)| (v + k * length, -k))).collect();
            match positive_until(&mirrored).map(|reach| length - reach) {
                // An undetermined sign within `|f| <= |f(p)| + last_zero <= PAD eps` of the start
                // is inside the bounds' padding.
                Some(last_zero) if last_zero <= lipschitz_reach || start.f.abs() + last_zero <= PAD * eps => (length, f_end.signum()),
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
        let lines: Few<(f64, f64)> = first.iter().zip(&last).map(|(a, b)| best_lower_line(a, b, piece, eps)).collect();
        // The chord of one triangle bounds min_T d_T from above; take the closest overall.
        let k = (0..first.len()).min_by(|&x, &y| (first[x].distance + last[x].distance).total_cmp(&(first[y].distance + last[y].distance))).expect("candidates");
        let chord = [first[k].distance + eps, last[k].distance + eps];
        // A candidate whose lower line stays above that chord is never the closest on the piece:
        // drop it (from the bounds, and from the point queries on this segment).
        // The chord's own triangle stays, whatever the rounding of its lines (found by fuzzing: a
        // tetrahedron with a vertex moved to 3e12 lost every candidate, a panic).
        let keep: Few<bool> = lines.iter().enumerate().map(|(j, (v, slope))| j == k || !(*v > chord[0] && v + slope * piece > chord[1])).collect();
        retain_flagged(&mut cache.candidates, &keep);
        retain_flagged(&mut first, &keep);
        retain_flagged(&mut last, &keep);
        let mut lines = lines;
        retain_flagged(&mut lines, &keep);
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
                // The normal (q − c)/|q − c| at any point of the piece is rounded by up to
                // ~4ε × coordinates / distance (found by fuzzing: a mesh 3e-46 wide queried
                // 2.5e-56 from an edge had normals 1e-5 rad off the bound's range): the range
                // widens by that at the piece's smallest distance, which the tangent lines of
                // the convex d_T bound from below.
                let (d0, d1) = (first[j].distance, last[j].distance);
                let floor = if k0 >= 0.0 {
                    d0
                } else if k1 <= 0.0 {
                    d1
                } else {
                    let s = ((d1 - d0 - k1 * piece) / (k0 - k1)).clamp(0.0, piece);
                    d0 + k0 * s
                };
                let coordinates = p.abs().max((p + piece * d).abs()).max(first[j].closest.point.abs()).max(last[j].closest.point.abs()).max_element();
                let rounding = 4.0 * f64::EPSILON * coordinates / floor.max(self.epsilon);
                // Monotone in exact arithmetic; order the ends against rounding.
                let (k0, k1) = (k0.min(k1) - rounding, k0.max(k1) + rounding);
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
        let end_closest = closest_of(&last);
        cache.hint = Some((p + piece * d, end_closest.triangle));
        let end = self.surface_point(p + piece * d, &end_closest);
        Ok(SegmentBound { length: piece, f_lo: pad(f_lo, -PAD * eps), f_hi: pad(f_hi, PAD * eps), cos, end: SegmentEnd::Point(end) })
    }

    /// Exact while the ray stays in the certified region of the triangle closest at `p`: up to
    /// the plane distance's crossing of `level`, else to the region's end.
    fn clearance(&self, start: &SurfacePoint, p: DVec3, d: DVec3, level: f64, cache: &mut MeshCache) -> f64 {
        let lipschitz = start.f - level;
        let Some(i) = Self::hint_at(cache, p) else { return lipschitz };
        let tri = &self.triangles[i as usize];
        let Some(piece) = self.regions[i as usize].piece(tri.n, p, d, f64::INFINITY) else { return lipschitz };
        // f = n·(q − p0) along the piece.
        let (f0, slope) = (tri.n.dot(p - tri.p[0]), tri.n.dot(d));
        let exact = if slope < 0.0 { ((f0 - level) / -slope).min(piece.length) } else { piece.length };
        (exact * (1.0 - 1e-9) - PAD * self.epsilon).max(lipschitz)
    }

    /// While the ray rises (or runs level) in the certified region of the triangle closest at
    /// `p`, `f` is its plane distance there, never below its start: the rest of that region.
    fn rising_clearance(&self, _start: &SurfacePoint, p: DVec3, d: DVec3, _level: f64, cache: &mut MeshCache) -> Option<f64> {
        let i = Self::hint_at(cache, p)?;
        let tri = &self.triangles[i as usize];
        if !(tri.n.dot(d) >= 0.0) {
            return None;
        }
        let piece = self.regions[i as usize].piece(tri.n, p, d, f64::INFINITY)?;
        let length = piece.length * (1.0 - 1e-9) - PAD * self.epsilon;
        (length > 0.0).then_some(length)
    }

    fn distance_bound(&self, p: DVec3) -> f64 {
        self.grid.distance_bound(p)
    }

    fn bounding_box(&self) -> Aabb {
        self.bounds
    }

    fn offset_enclosure(&self, level: f64) -> Option<super::Enclosure> {
        TriangleMesh::offset_enclosure(self, level)
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



#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;
    use macrofacet_validation::common::meshes;

    /// A uniformly distributed point of triangle `t`.
    fn point_on(t: &Triangle, rng: &mut Pcg32) -> DVec3 {
        let (u, v) = (rng.next_f64(), rng.next_f64());
        let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
        t.p[0] + u * (t.p[1] - t.p[0]) + v * (t.p[2] - t.p[0])
    }

    /// Where a face region certifies a point, its projection is the triangle's closest point:
    /// the same point, coordinates and distance as the general test's up to rounding, on the
    /// face (points near the surface of a smooth torus, a lumpy one and an L prism, whose
    /// reflex edges certify little).
    #[test]
    fn certified_projections_are_the_closest_points() {
        let mut rng = Pcg32::new(23, 4);
        for (name, mesh) in [("torus", meshes::torus(1.0, 0.4, 32, 16)), ("lumpy torus", meshes::lumpy_torus(1.0, 0.4, 32, 16, 0.15)), ("l_prism", meshes::l_prism())] {
            let s = TriangleMesh::new(&mesh.positions, &mesh.indices, mesh.normals.as_deref(), None, 1, f64::INFINITY).unwrap();
            let mut certified = 0;
            for _ in 0..20_000 {
                let i = (rng.next_f64() * s.triangles.len() as f64) as u32;
                let t = &s.triangles[i as usize];
                let p = point_on(t, &mut rng) + 0.05 * (2.0 * rng.next_f64() - 1.0).powi(3) * t.n;
                let Some(found) = s.regions[i as usize].certified_closest(t.n, p, i) else { continue };
                certified += 1;
                let exact = closest_on_triangle(t, p, i);
                let projected = s.regions[i as usize].face_closest(t.n, p, i);
                assert_eq!((found.point, found.barycentric, found.distance_sq), (projected.point, projected.barycentric, projected.distance_sq), "{name}");
                assert_eq!((found.triangle, found.feature), (i, Feature::Face), "{name}: {p}");
                assert!((found.point - exact.point).length() <= 1e-14, "{name}: {found:?} against {exact:?}");
                assert!((found.barycentric - exact.barycentric).abs().max_element() <= 1e-12, "{name}: {found:?} against {exact:?}");
                assert!((found.distance_sq.sqrt() - exact.distance_sq.sqrt()).abs() <= 1e-14, "{name}: {found:?} against {exact:?}");
            }
            // Not vacuous: most of these points lie in a certified region.
            assert!(certified > 10_000, "{name}: {certified} certified points of 20000");
        }
    }

    /// The grid's lists hold a closest triangle of every point of their cells, and its distance
    /// bound lies below the distance everywhere: points near and around a torus, a lumpy one,
    /// an L prism and a cube, against every triangle.
    #[test]
    fn grid_lists_hold_the_closest_triangle_and_its_bounds_hold() {
        let mut rng = Pcg32::new(41, 6);
        // Each mesh built for any medium, and for one that reaches a thousandth of its extent (its
        // lists then hold the closest triangle of the points within 4 reaches only, and the point
        // query finds the others through the hierarchy).
        let meshes = [("torus", meshes::torus(1.0, 0.4, 32, 16)), ("lumpy torus", meshes::lumpy_torus(1.0, 0.4, 32, 16, 0.15)), ("l_prism", meshes::l_prism()), ("cube", meshes::cube())];
        for ((name, mesh), reach) in meshes.iter().flat_map(|m| [(m, f64::INFINITY), (m, 1e-3)]) {
            let extent = (mesh.positions.iter().copied().fold(DVec3::NEG_INFINITY, DVec3::max) - mesh.positions.iter().copied().fold(DVec3::INFINITY, DVec3::min)).max_element();
            let s = TriangleMesh::new(&mesh.positions, &mesh.indices, None, None, 1, reach * extent).unwrap();
            let covered = s.grid.covered();
            assert_eq!(covered, REACH_MULTIPLE * reach * extent);
            let (mut listed, mut bounded) = (0, 0);
            for n in 0..8000 {
                // Half of them within a tenth of the extent of a face, half anywhere in the box
                // grown by half the extent on each side.
                let p = if n % 2 == 0 {
                    let t = &s.triangles[(rng.next_f64() * s.triangles.len() as f64) as usize];
                    point_on(t, &mut rng) + 0.1 * extent * (2.0 * rng.next_f64() - 1.0) * t.n
                } else {
                    let r = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
                    s.bounds.min - 0.5 * extent * DVec3::ONE + r * (s.bounds.max - s.bounds.min + extent * DVec3::ONE)
                };
                let exact = (0..s.triangles.len() as u32).map(|i| closest_on_triangle(&s.triangles[i as usize], p, i).distance_sq).fold(f64::INFINITY, f64::min);
                let lower = s.grid.distance_bound(p);
                assert!(lower <= exact.sqrt(), "{name}: the bound {lower} at {p} exceeds the distance {}", exact.sqrt());
                bounded += usize::from(lower > 0.0);
                if let Some(list) = s.grid.list_at(p).filter(|_| exact.sqrt() <= covered) {
                    listed += 1;
                    let among = list.iter().map(|&i| closest_on_triangle(&s.triangles[i as usize], p, i).distance_sq).fold(f64::INFINITY, f64::min);
                    assert_eq!(among, exact, "{name}, reach {reach}: the list at {p} misses the closest triangle");
                }
                // (A certified region's answer is its projection: rounded apart by a few ulps.)
                let (found, exact) = (s.closest(p, None).distance_sq.sqrt(), exact.sqrt());
                assert!((found - exact).abs() <= 1e-14 * extent, "{name}, reach {reach}: the point query at {p} found {found}, not the closest triangle's {exact}");
            }
            // Not vacuous: many points in listed cells, many with a positive bound (for the small
            // reach, the points near a face: a tenth of the extent up, a fortieth of them within
            // 4 reaches).
            let least = if reach == f64::INFINITY { 1500 } else { 40 };
            assert!(listed > least && bounded > 1000, "{name}, reach {reach}: {listed} points in listed cells, {bounded} with a positive bound, of 8000");
        }
    }

    /// A mesh built on several threads is the one built on one: its face regions, grid, edge
    /// zones and offset enclosure (a smooth torus with vertex normals, a lumpy one, and an L
    /// prism, whose few triangles keep to one thread).
    #[test]
    fn the_thread_count_does_not_change_the_surface() {
        for (name, mesh) in [("torus", meshes::torus(1.0, 0.4, 32, 16)), ("lumpy torus", meshes::lumpy_torus(1.0, 0.4, 48, 24, 0.15)), ("l_prism", meshes::l_prism())] {
            let build = |threads| TriangleMesh::new(&mesh.positions, &mesh.indices, mesh.normals.as_deref(), None, threads, f64::INFINITY).unwrap();
            let one = build(1);
            for threads in [2, 3, 8] {
                let many = build(threads);
                let same = |what: &str, a: String, b: String| assert!(a == b, "{name}: the {what} differ on {threads} threads");
                same("triangles", format!("{:?}", one.triangles), format!("{:?}", many.triangles));
                same("face regions", format!("{:?}", one.regions), format!("{:?}", many.regions));
                same("grids", format!("{:?}", one.grid), format!("{:?}", many.grid));
                same("edge zones", format!("{:?}", one.edges), format!("{:?}", many.edges));
                same("offset enclosures", format!("{:?}", one.offset_enclosure(0.01)), format!("{:?}", many.offset_enclosure(0.01)));
            }
        }
    }

    /// The meshes of the edge zones' tests, with their vertex normals and flat: a smooth torus,
    /// a lumpy one (saddles, concave edges) and a cube (right-angled edges).
    fn edge_test_surfaces() -> Vec<(&'static str, bool, TriangleMesh)> {
        let meshes = [("torus", meshes::torus(1.0, 0.4, 32, 16)), ("lumpy torus", meshes::lumpy_torus(1.0, 0.4, 32, 16, 0.15)), ("cube", meshes::cube())];
        let mut surfaces = Vec::new();
        for (name, mesh) in meshes {
            for shaded in [true, false] {
                let normals = mesh.normals.as_deref().filter(|_| shaded);
                surfaces.push((name, shaded, TriangleMesh::new(&mesh.positions, &mesh.indices, normals, None, 1, f64::INFINITY).unwrap()));
            }
        }
        surfaces
    }

    /// `bound` holds the mesh's `f` and the frame's `d·n` at 41 points of its segment from `p`,
    /// where `also` checks each point too.
    fn assert_bound_holds(s: &TriangleMesh, name: &str, p: DVec3, d: DVec3, bound: &SegmentBound, also: impl Fn(DVec3)) {
        let ((lo, lo_k), (hi, hi_k)) = (bound.lower_line(), bound.upper_line());
        for step in 0..=40 {
            let u = bound.length * step as f64 / 40.0;
            let q = s.point(p + u * d).unwrap();
            let tol = 1e-12 * (1.0 + q.f.abs());
            assert!(q.f >= lo + lo_k * u - tol && q.f <= hi + hi_k * u + tol, "{name}: f = {} outside [{}, {}] at {u} of {}", q.f, lo + lo_k * u, hi + hi_k * u, bound.length);
            let c = d.dot(q.normal);
            assert!(c >= bound.cos[0] - 1e-9 && c <= bound.cos[1] + 1e-9, "{name}: d·n = {c} outside {:?}", bound.cos);
            also(p + u * d);
        }
    }

    /// In an edge's zone the dihedral bound holds `f` and the frame's `d·n` along the whole
    /// segment, where the point queries of the whole mesh find one of the edge's two triangles:
    /// short segments across edges near the surface of a smooth torus (with its vertex normals
    /// and flat), a lumpy one (saddles, concave edges) and a cube (right-angled edges).
    #[test]
    fn dihedral_bounds_hold_in_edge_zones() {
        let mut rng = Pcg32::new(17, 2);
        for (name, shaded, s) in edge_test_surfaces() {
            let (mut checked, mut in_zone) = (0, 0);
            for _ in 0..6000 {
                let i = (rng.next_f64() * s.triangles.len() as f64) as usize;
                let k = (rng.next_f64() * 3.0) as usize;
                let zone = s.edges[i][k];
                let Some(curvature) = zone.curvature.filter(|_| zone.neighbour != u32::MAX) else { continue };
                let (t, j) = (&s.triangles[i], zone.neighbour);
                let (a, b) = (t.p[k], t.p[(k + 1) % 3]);
                let edge = (b - a).length();
                let across = t.n.cross(b - a).normalize();
                let normal = (t.n + s.triangles[j as usize].n).normalize();
                let x = a + (0.05 + 0.9 * rng.next_f64()) * (b - a);
                let p = x + edge * ((rng.next_f64() - 0.5) * 0.04 * normal + (rng.next_f64() - 0.5) * 0.1 * across);
                let d = DVec3::new(rng.next_f64() - 0.5, rng.next_f64() - 0.5, rng.next_f64() - 0.5).normalize();
                let length = edge * 10f64.powf(-4.0 + 3.0 * rng.next_f64());
                let end_p = p + length * d;
                if zone.piece(t, k, p, d, length, length) != Some(length) {
                    continue;
                }
                in_zone += 1;
                let start = s.point(p).unwrap();
                let end_closest = closest_among(&s.triangles, end_p, &[i as u32, j], Closest::NONE);
                let end = s.surface_point(end_p, &end_closest);
                // (The whole mesh's query may take the certified region's projection, the
                // same point up to rounding.)
                let query = s.point(end_p).unwrap();
                let same = (end.f - query.f).abs() <= 1e-12 * end.f.abs() + 1e-15 && (end.normal - query.normal).length() <= 1e-12;
                assert!(same, "{name}: the zone's pair missed the closest triangle: {end:?} against {query:?}");
                let at_start = [i as u32, j].map(|m| closest_on_triangle(&s.triangles[m as usize], p, m));
                let Some(bound) = s.dihedral_bound(&start, &at_start, &end, &end_closest, p, d, length, [i as u32, j], curvature) else { continue };
                checked += 1;
                assert_bound_holds(&s, &format!("{name} (shaded {shaded})"), p, d, &bound, |_| ());
            }
            println!("{name} (shaded {shaded}): {checked} dihedral bounds of {in_zone} segments in zones");
            // Not vacuous: most segments in a zone get the dihedral bound.
            assert!(in_zone > 500 && checked * 10 > in_zone * 8, "{name} (shaded {shaded}): {checked} dihedral bounds of {in_zone} segments in zones");
        }
    }

    /// A certified piece continued through an edge's zone in one segment (`through_zone`) holds
    /// `f` and the frame's `d·n` along the whole segment, where the point queries on it (the
    /// edge's two triangles) find the whole mesh's closest: segments from inside a face's region
    /// across one of its edges, on the meshes of `dihedral_bounds_hold_in_edge_zones`.
    #[test]
    fn bounds_through_edge_zones_hold() {
        let mut rng = Pcg32::new(23, 5);
        for (name, shaded, s) in edge_test_surfaces() {
            let mut merged = 0;
            for _ in 0..20_000 {
                let i = (rng.next_f64() * s.triangles.len() as f64) as usize;
                let k = (rng.next_f64() * 3.0) as usize;
                let t = &s.triangles[i];
                let (a, b) = (t.p[k], t.p[(k + 1) % 3]);
                let edge = (b - a).length();
                // Inward across edge k, in the plane.
                let inward = t.n.cross(b - a).normalize();
                let x = a + (0.1 + 0.8 * rng.next_f64()) * (b - a) + edge * 0.02 * rng.next_f64() * inward;
                let p = x + edge * (rng.next_f64() - 0.5) * 0.02 * t.n;
                // Heading out across the edge, at any angle to the plane.
                let d = (-inward * (0.2 + rng.next_f64()) + (rng.next_f64() - 0.5) * (b - a).normalize() + (rng.next_f64() - 0.5) * 0.6 * t.n).normalize();
                let length = edge * 10f64.powf(-2.5 + 1.5 * rng.next_f64());
                let mut cache = MeshCache::default();
                let start = s.start_point(p, &mut cache).unwrap();
                if cache.hint.map(|(_, c)| c) != Some(i as u32) {
                    continue;
                }
                let Ok(bound) = s.certified_bound(p, d, length, 1.0, &mut cache) else { continue };
                if cache.certified || cache.candidates.len() != 2 {
                    continue;
                }
                merged += 1;
                bound.validate(length, start.f, "the mesh").unwrap();
                assert_bound_holds(&s, &format!("{name} (shaded {shaded})"), p, d, &bound, |q| {
                    let on_segment = s.point_on_segment(q, &cache).unwrap();
                    let query = s.point(q).unwrap();
                    assert!((on_segment.f - query.f).abs() <= 1e-12 * (1.0 + query.f.abs()), "{name}: the segment's pair missed the closest triangle at {q}");
                });
            }
            println!("{name} (shaded {shaded}): {merged} bounds through edge zones");
            // Not vacuous.
            assert!(merged > 300, "{name} (shaded {shaded}): only {merged} bounds through edge zones");
        }
    }
}
