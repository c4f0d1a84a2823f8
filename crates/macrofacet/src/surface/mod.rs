//! Mean surfaces: the signed-distance field `f` whose zero set is the mean of a Gaussian-process
//! statistical surface (seeds/000 Sec. 3), with the local frame of its flakes.
//!
//! The tracker ([`crate::tracking`]) asks a surface two things:
//! - [`MeanSurface::point`]: `f(p)`, the unit frame normal `n(p)` (the gradient of `f`, or a
//!   smooth shading normal for meshes with vertex normals) and the tangent that carries
//!   `alpha_u` (Mitsuba's `dp/du`; any vector for isotropic roughness);
//! - [`MeanSurface::bound`]: conservative bounds of `f` and of `d·n` along a segment
//!   ([`SegmentBound`]), from which the tracker builds a majorant that is exact for a planar
//!   shell and still bounds `σ_t` on a curved one. Every surface can answer with the Lipschitz
//!   bound of a signed-distance function ([`SegmentBound::lipschitz`]); tighter answers make
//!   tracking cheaper, never biased.
//!
//! SDF sign (design notes): `f > 0` outside, `f < 0` inside. Every `f` here is 1-Lipschitz except
//! an interpolated grid's, which says how far from it it strays ([`MeanSurface::clearance`],
//! [`MeanSurface::bound`]).

mod convex;
mod enclosure;
mod grid;
mod mesh;
mod sphere;

pub use convex::{convex_bound, Curvature};
pub use enclosure::{enclosure, Enclosure};
pub use grid::GridSurface;
pub use mesh::TriangleMesh;
pub use sphere::Sphere;

use crate::error::{Error, ErrorKind, Result};
use glam::{DVec2, DVec3};

/// What a mean surface knows at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Signed distance to the mean surface (scene units).
    pub f: f64,
    /// Unit normal of the local frame (local `+z`).
    pub normal: DVec3,
    /// Direction of `alpha_u`; made orthogonal to `normal` by the frame (any vector, even zero,
    /// for isotropic roughness).
    pub tangent: DVec3,
    /// Texture coordinates of the closest point of the mean surface (Mitsuba's `uv`), for
    /// parameters painted over the surface.
    pub uv: DVec2,
}

/// Largest accepted `| |normal| − 1 |` of a mean-surface answer (hosts normalise in f32 or f64).
pub const NORMAL_TOLERANCE: f64 = 1e-4;

impl SurfacePoint {
    /// The point if it is usable at `p`: `f` not NaN, a unit normal, a finite tangent and uv
    /// (every query of a mean surface goes through this: the tracker's, `mf_surface_eval`'s and
    /// the enclosure's; found by fuzzing: a degenerate mesh or a far point gave a zero normal).
    #[inline]
    pub fn validated(self, p: DVec3) -> Result<SurfacePoint> {
        // |n| within NORMAL_TOLERANCE of 1, compared squared (no square root on the hot path);
        // a NaN or infinite normal fails it too.
        const LENGTH_SQ: [f64; 2] = [(1.0 - NORMAL_TOLERANCE) * (1.0 - NORMAL_TOLERANCE), (1.0 + NORMAL_TOLERANCE) * (1.0 + NORMAL_TOLERANCE)];
        let unit = (LENGTH_SQ[0]..=LENGTH_SQ[1]).contains(&self.normal.length_squared());
        // (Inlined, with the message out of line: the check is on every query of the tracker.)
        // x · 0 is 0 exactly when x is finite (∞ · 0 and NaN · 0 are NaN): one comparison for
        // the tangent and the uv, half the instructions of five is_finite.
        let (t, uv) = (self.tangent, self.uv);
        let finite = t.x * 0.0 + t.y * 0.0 + t.z * 0.0 + uv.x * 0.0 + uv.y * 0.0 == 0.0;
        if self.f.is_nan() || !unit || !finite {
            return Err(self.unusable(p));
        }
        Ok(self)
    }

    #[cold]
    #[inline(never)]
    fn unusable(&self, p: DVec3) -> Error {
        let len = self.normal.length();
        Error::new(
            ErrorKind::InvalidArgument,
            format!(
                "the mean surface at {p} returned f = {}, normal {} (length {len}), tangent {}, uv {}: f must not be NaN, the normal must be unit, the tangent and uv finite",
                self.f, self.normal, self.tangent, self.uv
            ),
        )
    }
}

/// Conservative bounds along the segment `p + s d`, `s ∈ [0, length]`:
/// `f_lo(s) <= f(p + s d) <= f_hi(s)` with `f_lo`, `f_hi` linear between their values at the two
/// ends, and `cos[0] <= d · n(p + s d) <= cos[1]` for the frame normal `n`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentBound {
    /// The length the bound holds for: at most the length asked for (a surface may shorten it).
    pub length: f64,
    /// Lower bound of `f` at `s = 0` and `s = length` (`-∞` allowed: no bound).
    pub f_lo: [f64; 2],
    /// Upper bound of `f` at `s = 0` and `s = length` (`+∞` allowed: no bound).
    pub f_hi: [f64; 2],
    /// Range of `d · n` along the segment, within `[-1, 1]`.
    pub cos: [f64; 2],
    /// What the bound knows of the surface at `s = length` (a known end saves the tracker a query
    /// at the start of the next segment).
    pub end: SegmentEnd,
}

/// The surface at a segment's end, as far as its bound computed it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SegmentEnd {
    /// Not computed: the tracker queries the surface there.
    Unknown,
    /// The surface point there, exactly.
    Point(SurfacePoint),
    /// `f` there, exactly as [`MeanSurface::point`] gives it; the rest of the point is left to
    /// [`MeanSurface::end_point`], which the tracker calls only when a segment starts there. Most
    /// tracking calls through a thin shell end within their first segment (a collision, or the
    /// exit, known from `f`), where the frame at its end went unused.
    Height(f64),
}

impl SegmentEnd {
    /// `f` at the end, where known.
    pub fn f(&self) -> Option<f64> {
        match self {
            SegmentEnd::Unknown => None,
            SegmentEnd::Point(point) => Some(point.f),
            SegmentEnd::Height(f) => Some(*f),
        }
    }
}

impl SegmentBound {
    /// The bound every `L`-Lipschitz `f` admits (`L = 1` for a signed distance,
    /// [`MeanSurface::lipschitz`]): `|f(p + s d) − f(p)| <= L s`, any frame.
    pub fn lipschitz(f0: f64, length: f64, constant: f64) -> SegmentBound {
        SegmentBound {
            length,
            f_lo: [f0, f0 - constant * length],
            f_hi: [f0, f0 + constant * length],
            cos: [-1.0, 1.0],
            end: SegmentEnd::Unknown,
        }
    }

    /// `f_lo(s)` as `(value at 0, slope)`.
    pub fn lower_line(&self) -> (f64, f64) {
        line(self.f_lo, self.length)
    }

    /// `f_hi(s)` as `(value at 0, slope)`; the value is `+∞` without an upper bound.
    pub fn upper_line(&self) -> (f64, f64) {
        line(self.f_hi, self.length)
    }

    /// Checks what a surface returned: finite lengths, ordered lines, a cosine range in
    /// `[-1, 1]`, and consistency with the known value `f0` at the start. `what` names the
    /// surface in the message.
    /// (Inlined, with each message formatted out of line: the check is on every segment.)
    #[inline]
    pub fn validate(&self, asked: f64, f0: f64, what: &str) -> Result<()> {
        if !(self.length > 0.0 && self.length <= asked) {
            return Err(bad_bound(what, format_args!("length must lie in (0, {asked}], got {}", self.length)));
        }
        if self.f_lo.iter().any(|v| v.is_nan() || *v == f64::INFINITY) || self.f_hi.iter().any(|v| v.is_nan() || *v == f64::NEG_INFINITY) {
            return Err(bad_bound(what, format_args!("f_lo must be < +inf and f_hi > -inf, not NaN; got f_lo {:?}, f_hi {:?}", self.f_lo, self.f_hi)));
        }
        // 1e-9 relative slack: hosts compute the bound and the point in different roundings.
        let slack = 1e-9 * (1.0 + f0.abs());
        if self.f_lo[0] > f0 + slack || self.f_hi[0] < f0 - slack {
            return Err(bad_bound(what, format_args!("[{}, {}] at the start does not contain f = {f0}", self.f_lo[0], self.f_hi[0])));
        }
        if !(self.cos[0] >= -1.0 - 1e-9 && self.cos[1] <= 1.0 + 1e-9 && self.cos[0] <= self.cos[1]) {
            return Err(bad_bound(what, format_args!("cos range must be an ordered range within [-1, 1], got {:?}", self.cos)));
        }
        Ok(())
    }
}

/// The error of a segment bound that [`SegmentBound::validate`] refuses, formatted here.
#[cold]
#[inline(never)]
fn bad_bound(what: &str, problem: std::fmt::Arguments) -> Error {
    Error::new(ErrorKind::InvalidArgument, format!("{what}: segment bound {problem}"))
}

fn line(ends: [f64; 2], length: f64) -> (f64, f64) {
    if ends[0].is_infinite() || ends[1].is_infinite() {
        return (ends[0], 0.0);
    }
    (ends[0], (ends[1] - ends[0]) / length)
}

/// An axis-aligned box; infinite coordinates for unbounded surfaces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: DVec3,
    pub max: DVec3,
}

impl Aabb {
    pub const EVERYTHING: Aabb = Aabb { min: DVec3::NEG_INFINITY, max: DVec3::INFINITY };

    pub fn grown(&self, by: f64) -> Aabb {
        Aabb { min: self.min - DVec3::splat(by), max: self.max + DVec3::splat(by) }
    }

    /// [`MeanSurface::clip_region`] of a surface whose box (of `f <= 0`) this is: the box grown
    /// by `reach` (and 1e-9 of it, for the rounding of `f`).
    #[inline]
    pub fn clip_region(&self, o: DVec3, d: DVec3, t_max: f64, reach: f64) -> Option<(f64, f64)> {
        self.grown(reach * (1.0 + 1e-9)).clip(o, d, 0.0, t_max)
    }

    /// The parameter interval of `o + t d` inside the box, clipped to `[t0, t1]`; `None` when
    /// the ray misses it.
    pub fn clip(&self, o: DVec3, d: DVec3, t0: f64, t1: f64) -> Option<(f64, f64)> {
        let (mut lo, mut hi) = (t0, t1);
        // (Arrays: indexing a DVec3 by a loop variable costs a match per access.)
        let (min, max, o, d) = (self.min.to_array(), self.max.to_array(), o.to_array(), d.to_array());
        for a in 0..3 {
            let (bmin, bmax, oa, da) = (min[a], max[a], o[a], d[a]);
            // (An unbounded axis never rejects: o is finite.)
            if da == 0.0 {
                if oa < bmin || oa > bmax {
                    return None;
                }
                continue;
            }
            if bmin == f64::NEG_INFINITY && bmax == f64::INFINITY {
                continue;
            }
            let inv = 1.0 / da;
            let (ta, tb) = ((bmin - oa) * inv, (bmax - oa) * inv);
            // Entry and exit by the sign of d; comparisons that leave lo and hi alone when a
            // product is NaN (a subnormal d whose inverse overflows, at a face).
            let (near, far) = if inv > 0.0 { (ta, tb) } else { (tb, ta) };
            if near > lo {
                lo = near;
            }
            if far < hi {
                hi = far;
            }
        }
        (lo <= hi).then_some((lo, hi))
    }
}

/// A mean surface the tracker can query. Implementations must be cheap to call and
/// deterministic; `Cache` holds per-query state (e.g. a mesh's candidate triangles for the
/// current segment), created by the tracker for each tracked segment of rays.
pub trait MeanSurface {
    type Cache: Default;

    /// The surface at `p`.
    fn point(&self, p: DVec3) -> Result<SurfacePoint>;

    /// The surface at `p` where the tracker starts a segment: as [`Self::point`], and may note
    /// in `cache` what helps the [`Self::bound`] at `p` that follows.
    fn start_point(&self, p: DVec3, _cache: &mut Self::Cache) -> Result<SurfacePoint> {
        self.point(p)
    }

    /// The surface at a point of the segment of the last [`Self::bound`] call with this `cache`;
    /// may use the cache to answer faster, must answer as [`Self::point`] (but for `uv`, see
    /// [`Self::uv`]), up to the rounding of another way to the same closest point (a mesh's
    /// certified projection).
    fn point_on_segment(&self, p: DVec3, _cache: &Self::Cache) -> Result<SurfacePoint> {
        self.point(p)
    }

    /// The surface at the end `p` of the last [`Self::bound`] call with this `cache`, where that
    /// bound's end was [`SegmentEnd::Height`] and a segment starts there: as
    /// [`Self::start_point`] (which answers it for any surface), from what the bound left in the
    /// cache.
    fn end_point(&self, p: DVec3, cache: &mut Self::Cache) -> Result<SurfacePoint> {
        self.start_point(p, cache)
    }

    /// Where the last query with `cache` found the surface, as a value that a later call starting
    /// at that point may hand to [`Self::seed_cache`] (a mesh: the triangle of its segment); 0
    /// when the surface has nothing worth handing on.
    fn hint(&self, _cache: &Self::Cache) -> u64 {
        0
    }

    /// Seeds a fresh `cache` with a [`Self::hint`]: the call's first query begins its search
    /// there. Any value is safe (a stale or foreign one costs at most the search it fails to
    /// save): answers are the same, up to the rounding of another way to the same closest point.
    fn seed_cache(&self, _cache: &mut Self::Cache, _hint: u64) {}

    /// The texture coordinates at `p`, where a query answered `point`. A surface whose `uv`
    /// costs more than the rest of a query (a sphere's two angles) may leave it zero in
    /// [`Self::start_point`], [`Self::point_on_segment`] and [`SegmentBound::end`] and give it
    /// here: the tracker asks only where a field reads it. [`Self::point`] always fills it.
    fn uv(&self, _p: DVec3, point: &SurfacePoint) -> DVec2 {
        point.uv
    }

    /// Bounds along `p + s d`, `s ∈ [0, length]`, where `start = point(p)` (`d` unit). The
    /// tracker prefers bounds whose width `f_hi − f_lo` stays within `tolerance`; a surface may
    /// shorten the segment to get there, or when bounding the whole of it would be costly.
    fn bound(&self, start: &SurfacePoint, p: DVec3, d: DVec3, length: f64, tolerance: f64, cache: &mut Self::Cache) -> Result<SegmentBound>;

    /// How far along `d` from `p` (where `start = point(p)` and `start.f > level`) `f` stays
    /// above `level`. Every surface allows `(start.f − level) / L` ([`Self::lipschitz`]); one
    /// that knows `f` along the ray may say more (up to `+∞`: never below `level`).
    fn clearance(&self, start: &SurfacePoint, _p: DVec3, _d: DVec3, level: f64, _cache: &mut Self::Cache) -> f64 {
        (start.f - level) / self.lipschitz()
    }

    /// A distance along `d` from `p` (where `start = point(p)` and `start.f > level`) over which
    /// `f` provably does not fall below `level`, from what the surface knows exactly there (not
    /// from its Lipschitz bound); `None` when it knows nothing more. The tracker steps by it even
    /// right above the top face: a ray leaving the shell crosses the empty space beside it
    /// without bounding empty segments.
    fn rising_clearance(&self, _start: &SurfacePoint, _p: DVec3, _d: DVec3, _level: f64, _cache: &mut Self::Cache) -> Option<f64> {
        None
    }

    /// True when [`Self::clearance`] is the ray's first crossing of `level` (up to rounding),
    /// not a step within a neighbourhood: one step then crosses any empty space above the shell,
    /// and the tracker takes it even right above the top face.
    fn exact_clearance(&self) -> bool {
        false
    }

    /// A Lipschitz constant of `f` over all space: 1 for a signed distance; an interpolated
    /// grid's can be larger.
    fn lipschitz(&self) -> f64 {
        1.0
    }

    /// True when every point's frame normal is the direction of `∇f`: where a ray descends, `d·n`
    /// is then negative ([`crate::opaque_core`]). A mesh's vertex normals are not.
    fn normal_is_gradient(&self) -> bool {
        false
    }

    /// A lower bound of `|f(p)|`, cheaper than [`Self::point`] (0 when unknown): lets the
    /// tracker cross empty space above the shell without exact queries.
    fn distance_bound(&self, _p: DVec3) -> f64 {
        0.0
    }

    /// A box containing every point with `f <= 0` (the mean surface and its interior). Since `f`
    /// is a signed distance, the box grown by `top` contains the medium's region `f < top`.
    /// [`Aabb::EVERYTHING`] when the interior is unbounded.
    fn bounding_box(&self) -> Aabb;

    /// The part of `[0, t_max]` (`t_max` at most `f64::MAX`) of the ray `o + t d` (`d` unit)
    /// inside a region that contains every point with `f <= reach` (`reach >= 0`), or `None`
    /// where the ray misses it: [`Self::bounding_box`] grown by `reach` unless the surface knows
    /// a tighter region that is as cheap to clip.
    fn clip_region(&self, o: DVec3, d: DVec3, t_max: f64, reach: f64) -> Option<(f64, f64)> {
        self.bounding_box().clip_region(o, d, t_max, reach)
    }

    /// An enclosure of `f < level` tighter than the grid's of [`enclosure`], when the surface
    /// can build one and prove it conservative (a mesh: its own faces moved out, `mesh/offset.rs`);
    /// `None` otherwise.
    fn offset_enclosure(&self, _level: f64) -> Option<Enclosure> {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::Aabb;
    use crate::rng::Pcg32;
    use glam::DVec3;

    /// The slab test written plainly (as `clip` was): per bounded axis, the sorted interval of `t`.
    fn clip_reference(b: &Aabb, o: DVec3, d: DVec3, t0: f64, t1: f64) -> Option<(f64, f64)> {
        let (mut lo, mut hi) = (t0, t1);
        for a in 0..3 {
            if b.min[a] == f64::NEG_INFINITY && b.max[a] == f64::INFINITY {
                continue;
            }
            if d[a] == 0.0 {
                if o[a] < b.min[a] || o[a] > b.max[a] {
                    return None;
                }
                continue;
            }
            let inv = 1.0 / d[a];
            let (mut ta, mut tb) = ((b.min[a] - o[a]) * inv, (b.max[a] - o[a]) * inv);
            if ta > tb {
                std::mem::swap(&mut ta, &mut tb);
            }
            lo = lo.max(ta);
            hi = hi.min(tb);
        }
        (lo <= hi).then_some((lo, hi))
    }

    #[test]
    fn clip_agrees_with_the_plain_slab_test() {
        let mut rng = Pcg32::new(7, 11);
        let mut u = move || 2.0 * rng.next_f64() - 1.0;
        let boxes = [
            Aabb { min: DVec3::new(-1.0, -2.0, -0.5), max: DVec3::new(1.0, 0.5, 3.0) },
            Aabb { min: DVec3::new(f64::NEG_INFINITY, -1.0, f64::NEG_INFINITY), max: DVec3::new(f64::INFINITY, 1.0, f64::INFINITY) },
            Aabb::EVERYTHING,
        ];
        let (mut hits, mut misses) = (0, 0);
        for b in &boxes {
            for i in 0..4000 {
                let o = 3.0 * DVec3::new(u(), u(), u());
                let mut d = DVec3::new(u(), u(), u());
                // Axis-parallel rays, and rays along the box's faces.
                if i % 5 == 0 {
                    d.x = 0.0;
                }
                if i % 7 == 0 {
                    d.y = 0.0;
                }
                let d = d.normalize_or(DVec3::Z);
                let o = if i % 11 == 0 && b.min.x.is_finite() { DVec3::new(b.min.x, o.y, o.z) } else { o };
                let (t0, t1) = if i % 3 == 0 { (0.0, f64::INFINITY) } else { (0.0, 2.0 * u().abs()) };
                let (got, want) = (b.clip(o, d, t0, t1), clip_reference(b, o, d, t0, t1));
                assert_eq!(got, want, "box {b:?}, o {o}, d {d}, [{t0}, {t1}]");
                if got.is_some() {
                    hits += 1;
                } else {
                    misses += 1;
                }
            }
        }
        assert!(hits > 1000 && misses > 1000, "{hits} hits, {misses} misses: the cases must exercise both");
        // A ray on a face with a subnormal component along its normal: the inverse overflows, the
        // face's product is NaN (0 × ∞), which must not close the interval: the ray stays on the
        // closed box's face.
        let b = &boxes[0];
        let (o, d) = (DVec3::new(1.0, 0.0, 0.0), DVec3::new(f64::MIN_POSITIVE / 4.0, 0.6, 0.8));
        assert_eq!(b.clip(o, d, 0.0, 10.0), Some((0.0, 0.5 / 0.6)));
        assert_eq!(b.clip(o, d, 0.0, 10.0), clip_reference(b, o, d, 0.0, 10.0));
    }
}
