//! `mf_surface`: the mean surface a macrofacet medium lives on, for the tracking calls.
//!
//! Three kinds, one handle type:
//! - a sphere ([`mf_surface_new_sphere`]) and a triangle mesh ([`mf_surface_new_mesh`]) built
//!   into the library, with exact signed distances and rigorous segment bounds;
//! - host callbacks ([`mf_surface_new_callbacks`]): the host's own signed distance, called with
//!   the `user_data` of each tracking call. Its segment bounds come from a bound callback, or
//!   from convexity (`MF_SURFACE_CONVEX` / `MF_SURFACE_CONCAVE`: two point queries per segment),
//!   or from the Lipschitz bound every signed distance has (`MF_SURFACE_GENERAL`).
//!
//! Conventions: `f > 0` outside, `f` a signed distance (1-Lipschitz), `normal` the unit frame
//! normal (the gradient of `f`, except for meshes with vertex normals: the interpolated normal at
//! the closest point, as Mitsuba 3 shades), `tangent` the direction of `alpha_u` (Mitsuba's
//! `dp/du`; any vector for isotropic roughness).

use super::medium::mf_vec3;
use super::{arg, boundary, free_handle, into_handle, mf_status, out, FfiError, FfiResult};
use macrofacet::error::{Error, ErrorKind, Result};
use macrofacet::surface::{convex_bound, enclosure, Aabb, Curvature, Enclosure, GridSurface, MeanSurface, SegmentBound, SegmentEnd, Sphere, SurfacePoint, TriangleMesh};
use glam::{DMat3, DVec2, DVec3};
use std::ffi::c_void;

/// [`mf_surface_callbacks::shape`]: no known curvature; without a bound callback the tracker
/// uses the Lipschitz bound `|f(p + s d) − f(p)| <= s` (correct, slower).
pub const MF_SURFACE_GENERAL: u32 = 0;
/// `f` is convex along every line (a convex solid with outward normals, e.g. a sphere or box),
/// and `normal` is its gradient: bounds come from the segment's two end points.
pub const MF_SURFACE_CONVEX: u32 = 1;
/// `f` is concave along every line (a convex solid with inward normals), `normal = ∇f`.
pub const MF_SURFACE_CONCAVE: u32 = 2;

/// The mean surface at a point.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct mf_surface_point {
    /// Signed distance to the mean surface (scene units; `> 0` outside).
    pub f: f64,
    /// Unit normal of the local frame.
    pub normal: mf_vec3,
    /// Direction of `alpha_u` (made orthogonal to `normal` by the library).
    pub tangent: mf_vec3,
    /// Texture coordinates of the closest point of the mean surface (for fields painted over
    /// the surface; a host surface may leave them at the 0 the library sets before the call).
    pub u: f64,
    pub v: f64,
}

/// Conservative bounds along the segment `p + s d`, `s ∈ [0, length]`: `f` lies between the
/// lines through `(0, f_lo[0])`, `(length, f_lo[1])` and through `(0, f_hi[0])`,
/// `(length, f_hi[1])`; `d · normal` lies in `[cos_lo, cos_hi]`. `length` may be shorter than
/// asked for. `f_lo` may be `-inf` and `f_hi` `+inf` (no bound on that side).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct mf_segment_bound {
    pub length: f64,
    pub f_lo: [f64; 2],
    pub f_hi: [f64; 2],
    pub cos_lo: f64,
    pub cos_hi: f64,
}

/// The host's mean surface at `p` (world space): writes `*out` and returns 0, or returns any
/// non-zero code to report a failure (the tracking call then fails with `MF_ERROR_CALLBACK`).
/// Must not unwind.
pub type mf_surface_point_fn = Option<unsafe extern "C" fn(user_data: *mut c_void, p: mf_vec3, out: *mut mf_surface_point) -> i32>;

/// The host's bound of the segment `p + s d`, `s ∈ [0, length]`, where `*start` is the surface
/// at `p`: writes `*out` and returns 0, or a non-zero code on failure. The tracker prefers
/// bounds with `f_hi − f_lo <= tolerance` and accepts a shorter `length`. Must not unwind.
pub type mf_surface_bound_fn = Option<
    unsafe extern "C" fn(
        user_data: *mut c_void,
        start: *const mf_surface_point,
        p: mf_vec3,
        d: mf_vec3,
        length: f64,
        tolerance: f64,
        out: *mut mf_segment_bound,
    ) -> i32,
>;

/// A mean surface implemented by the host.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct mf_surface_callbacks {
    /// Required.
    pub point: mf_surface_point_fn,
    /// Optional (NULL: bounds from `shape`).
    pub bound: mf_surface_bound_fn,
    /// `MF_SURFACE_GENERAL`, `MF_SURFACE_CONVEX` or `MF_SURFACE_CONCAVE`; used without `bound`.
    pub shape: u32,
    /// A box containing the mean surface and its interior (`f <= 0`); infinite components for
    /// an unbounded interior. The tracker clips rays to it grown by the shell's top.
    pub bounds_min: mf_vec3,
    pub bounds_max: mf_vec3,
}

/// A triangle mesh for [`mf_surface_new_mesh`], in world space. Triangles are counter-clockwise
/// seen from outside (normals point out). The mesh must be closed and consistently wound (each
/// edge crossed as often in one direction as in the other) with a positive volume: an open,
/// inconsistently wound or inside-out mesh is refused with the reason.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct mf_mesh {
    /// `3 * vertex_count` doubles.
    pub positions: *const f64,
    pub vertex_count: usize,
    /// `3 * triangle_count` vertex indices.
    pub indices: *const u32,
    pub triangle_count: usize,
    /// NULL, or `3 * vertex_count` doubles: unit vertex normals (the frame normal is then their
    /// interpolation at the closest point, as Mitsuba 3 shades meshes).
    pub normals: *const f64,
    /// NULL, or `2 * vertex_count` doubles: texture coordinates (the tangent is then `dp/du`).
    pub uvs: *const f64,
}

/// A signed-distance grid for [`mf_surface_new_grid`] (Mitsuba 3's `sdfgrid`): `nx × ny × nz`
/// samples (each at least 2) at the corners of a regular grid over the unit cube of object
/// space, `x` fastest then `y` then `z` (the order of Mitsuba's `.vol` files), in object units;
/// `to_world` (row-major 3×4: linear part and translation) must be a rotation times a uniform
/// scale. Every sample on the grid's outer faces must be positive (the surface lies inside).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct mf_grid {
    pub values: *const f32,
    pub nx: usize,
    pub ny: usize,
    pub nz: usize,
    pub to_world: [f64; 12],
}

/// A mean surface. Immutable and safe to share between threads (the callbacks of a callback
/// surface must then be thread-safe, or be given per-thread `user_data`).
pub struct mf_surface {
    pub(crate) inner: SurfaceKind,
}

pub(crate) enum SurfaceKind {
    Sphere(Sphere),
    Mesh(Box<TriangleMesh>),
    Grid(Box<GridSurface>),
    Callbacks(Callbacks),
}

/// Validated host callbacks.
#[derive(Clone, Copy)]
pub(crate) struct Callbacks {
    point: unsafe extern "C" fn(*mut c_void, mf_vec3, *mut mf_surface_point) -> i32,
    bound: mf_surface_bound_fn,
    curvature: Option<Curvature>,
    bounds: Aabb,
}

/// [`Callbacks`] with the `user_data` of one call.
pub(crate) struct CallbackSurface {
    callbacks: Callbacks,
    user_data: *mut c_void,
}

impl CallbackSurface {
    pub(crate) fn new(callbacks: Callbacks, user_data: *mut c_void) -> Self {
        CallbackSurface { callbacks, user_data }
    }
}

fn callback_failed(what: &str, code: i32) -> Error {
    Error::new(ErrorKind::Callback, format!("the surface's {what} callback returned {code}"))
}

impl From<mf_surface_point> for SurfacePoint {
    fn from(p: mf_surface_point) -> SurfacePoint {
        SurfacePoint { f: p.f, normal: p.normal.into(), tangent: p.tangent.into(), uv: DVec2::new(p.u, p.v) }
    }
}

impl From<SurfacePoint> for mf_surface_point {
    fn from(p: SurfacePoint) -> mf_surface_point {
        mf_surface_point { f: p.f, normal: p.normal.into(), tangent: p.tangent.into(), u: p.uv.x, v: p.uv.y }
    }
}

impl MeanSurface for CallbackSurface {
    type Cache = ();

    fn point(&self, p: DVec3) -> Result<SurfacePoint> {
        let mut out = mf_surface_point { f: f64::NAN, normal: DVec3::ZERO.into(), tangent: DVec3::ZERO.into(), u: 0.0, v: 0.0 };
        // SAFETY: the host registered a callable function; it writes one mf_surface_point.
        let code = unsafe { (self.callbacks.point)(self.user_data, p.into(), &mut out) };
        if code != 0 {
            return Err(callback_failed("point", code));
        }
        Ok(out.into())
    }

    fn bound(&self, start: &SurfacePoint, p: DVec3, d: DVec3, length: f64, tolerance: f64, _: &mut ()) -> Result<SegmentBound> {
        if let Some(bound) = self.callbacks.bound {
            let c_start: mf_surface_point = (*start).into();
            let mut out = mf_segment_bound { length: f64::NAN, f_lo: [f64::NAN; 2], f_hi: [f64::NAN; 2], cos_lo: f64::NAN, cos_hi: f64::NAN };
            // SAFETY: as for `point`.
            let code = unsafe { bound(self.user_data, &c_start, p.into(), d.into(), length, tolerance, &mut out) };
            if code != 0 {
                return Err(callback_failed("bound", code));
            }
            return Ok(SegmentBound { length: out.length, f_lo: out.f_lo, f_hi: out.f_hi, cos: [out.cos_lo, out.cos_hi], end: SegmentEnd::Unknown });
        }
        match self.callbacks.curvature {
            Some(curvature) => {
                let end = self.point(p + length * d)?;
                Ok(convex_bound(start, &end, d, length, curvature))
            }
            None => Ok(SegmentBound::lipschitz(start.f, length, self.lipschitz())),
        }
    }

    fn bounding_box(&self) -> Aabb {
        self.callbacks.bounds
    }
}

fn invalid(message: String) -> FfiError {
    Error::new(ErrorKind::InvalidArgument, message).into()
}

/// Reads `n` doubles starting at `ptr`, naming `name` when NULL.
///
/// # Safety
/// `ptr` must be NULL or valid for `n` reads.
unsafe fn doubles<'a>(ptr: *const f64, n: usize, name: &str) -> FfiResult<&'a [f64]> {
    if ptr.is_null() {
        return Err(FfiError::null(name));
    }
    // SAFETY: non-NULL, and the caller promises n readable doubles.
    Ok(unsafe { std::slice::from_raw_parts(ptr, n) })
}

/// Creates a host-implemented surface (see [`mf_surface_callbacks`]).
///
/// # Safety
/// `callbacks` must be NULL or valid; `out_surface` NULL or valid for writes.
#[no_mangle]
pub unsafe extern "C" fn mf_surface_new_callbacks(callbacks: *const mf_surface_callbacks, out_surface: *mut *mut mf_surface) -> mf_status {
    boundary(|| {
        let c = arg(callbacks, "callbacks")?;
        let slot = out(out_surface, "out_surface")?;
        let point = c.point.ok_or_else(|| FfiError::null("callbacks->point"))?;
        let curvature = match c.shape {
            MF_SURFACE_GENERAL => None,
            MF_SURFACE_CONVEX => Some(Curvature::Convex),
            MF_SURFACE_CONCAVE => Some(Curvature::Concave),
            other => return Err(invalid(format!("callbacks->shape must be MF_SURFACE_GENERAL, MF_SURFACE_CONVEX or MF_SURFACE_CONCAVE, got {other}"))),
        };
        let (min, max) = (DVec3::from(c.bounds_min), DVec3::from(c.bounds_max));
        if min.is_nan() || max.is_nan() || (0..3).any(|i| !(min[i] <= max[i])) || (0..3).any(|i| min[i] == f64::INFINITY || max[i] == f64::NEG_INFINITY) {
            return Err(invalid(format!("callbacks->bounds_min {min} / bounds_max {max} must be an ordered box (infinite sides allowed)")));
        }
        *slot = into_handle(mf_surface { inner: SurfaceKind::Callbacks(Callbacks { point, bound: c.bound, curvature, bounds: Aabb { min, max } }) });
        Ok(())
    })
}

/// Creates a sphere: `f = |p − center| − radius` (negated when `flip_normals`, which makes the
/// outside the interior), frame normal `∇f`, tangent `pole × (p − center)` — Mitsuba 3's `dp/du`
/// when `pole` is the sphere's object-space `+z` axis in world space.
///
/// # Safety
/// `out_surface` must be NULL or valid for writes.
#[no_mangle]
pub unsafe extern "C" fn mf_surface_new_sphere(center: mf_vec3, radius: f64, flip_normals: bool, pole: mf_vec3, out_surface: *mut *mut mf_surface) -> mf_status {
    boundary(|| {
        let slot = out(out_surface, "out_surface")?;
        let sphere = Sphere::new(center.into(), radius, flip_normals, pole.into())?;
        *slot = into_handle(mf_surface { inner: SurfaceKind::Sphere(sphere) });
        Ok(())
    })
}

/// The most threads [`mf_surface_new_mesh`] accepts.
pub const MF_MAX_BUILD_THREADS: usize = 1024;

/// Creates a triangle-mesh surface (exact signed distance, see [`mf_mesh`]). The arrays are
/// copied; the caller may free them after the call. `threads` is the most threads the
/// construction may use, the calling one among them (0 or 1: the calling thread only; at most
/// [`MF_MAX_BUILD_THREADS`]), and the surface's enclosures ([`mf_surface_enclosure`]) later
/// use as many. The surface is the same whatever the count; the threads end before the call
/// returns. `reach` is the largest distance from the mesh at which the media using the surface
/// will be tracked: a macrofacet medium's shell top (`mf_medium_shell_top`; the largest of
/// several media's), `INFINITY` when unknown. The surface builds its fast closed forms up to a
/// few reaches from the mesh (a thin shell's surface builds in about a quarter less time) and
/// searches beyond: its distances, gradients and frames do not depend on it (up to rounding),
/// though a tracking call's segments may split differently, so that one seed may draw
/// different, equally distributed, events. Building costs 30 to 50 µs of one core per triangle
/// at no limit. Refused with the reason: a mesh that is not closed, non-finite or out-of-range
/// data, vertices beyond ±1e50, a mesh narrower than 1e-50 (lengths outside the range of
/// `sigma`), too many threads, a reach that is NaN, zero or negative.
///
/// # Safety
/// `mesh` must be NULL or valid, its arrays valid for the sizes it states.
#[no_mangle]
pub unsafe extern "C" fn mf_surface_new_mesh(mesh: *const mf_mesh, threads: usize, reach: f64, out_surface: *mut *mut mf_surface) -> mf_status {
    boundary(|| {
        let m = arg(mesh, "mesh")?;
        let slot = out(out_surface, "out_surface")?;
        if threads > MF_MAX_BUILD_THREADS {
            return Err(invalid(format!("threads must be at most {MF_MAX_BUILD_THREADS}, got {threads}")));
        }
        let (nv, nt) = (m.vertex_count, m.triangle_count);
        let too_big = |what: &str| invalid(format!("mesh->{what} is too large"));
        let (n3v, n2v, n3t) = (nv.checked_mul(3).ok_or_else(|| too_big("vertex_count"))?, nv.checked_mul(2).ok_or_else(|| too_big("vertex_count"))?, nt.checked_mul(3).ok_or_else(|| too_big("triangle_count"))?);
        if nt == 0 || nv == 0 {
            return Err(invalid(format!("the mesh needs vertices and triangles, got {nv} vertices and {nt} triangles")));
        }
        // SAFETY: the caller promises the sizes stated in `mesh`.
        let positions = unsafe { doubles(m.positions, n3v, "mesh->positions") }?;
        let indices = if m.indices.is_null() {
            return Err(FfiError::null("mesh->indices"));
        } else {
            // SAFETY: as above.
            unsafe { std::slice::from_raw_parts(m.indices, n3t) }
        };
        let normals = if m.normals.is_null() { None } else { Some(unsafe { doubles(m.normals, n3v, "mesh->normals") }?) };
        let uvs = if m.uvs.is_null() { None } else { Some(unsafe { doubles(m.uvs, n2v, "mesh->uvs") }?) };
        let positions: Vec<DVec3> = positions.chunks_exact(3).map(DVec3::from_slice).collect();
        let triangles: Vec<[u32; 3]> = indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
        let normals: Option<Vec<DVec3>> = normals.map(|n| n.chunks_exact(3).map(DVec3::from_slice).collect());
        let uvs: Option<Vec<DVec2>> = uvs.map(|uv| uv.chunks_exact(2).map(DVec2::from_slice).collect());
        let surface = TriangleMesh::new(&positions, &triangles, normals.as_deref(), uvs.as_deref(), threads, reach).map_err(|e| Error::new(e.kind, format!("mesh: {}", e.message)))?;
        *slot = into_handle(mf_surface { inner: SurfaceKind::Mesh(Box::new(surface)) });
        Ok(())
    })
}

/// Creates a signed-distance-grid surface (trilinear; see [`mf_grid`]). The values are copied.
///
/// # Safety
/// `grid` must be NULL or valid, `grid->values` valid for `nx * ny * nz` reads.
#[no_mangle]
pub unsafe extern "C" fn mf_surface_new_grid(grid: *const mf_grid, out_surface: *mut *mut mf_surface) -> mf_status {
    boundary(|| {
        let g = arg(grid, "grid")?;
        let slot = out(out_surface, "out_surface")?;
        let count = g.nx.checked_mul(g.ny).and_then(|n| n.checked_mul(g.nz)).ok_or_else(|| invalid(format!("grid dimensions {} x {} x {} are too large", g.nx, g.ny, g.nz)))?;
        if g.values.is_null() {
            return Err(FfiError::null("grid->values"));
        }
        // SAFETY: non-NULL, and the caller promises nx * ny * nz readable floats.
        let values = unsafe { std::slice::from_raw_parts(g.values, count) };
        let m = g.to_world;
        let linear = DMat3::from_cols(DVec3::new(m[0], m[4], m[8]), DVec3::new(m[1], m[5], m[9]), DVec3::new(m[2], m[6], m[10]));
        let surface = GridSurface::new(values, [g.nx, g.ny, g.nz], linear, DVec3::new(m[3], m[7], m[11])).map_err(|e| Error::new(e.kind, format!("grid: {}", e.message)))?;
        *slot = into_handle(mf_surface { inner: SurfaceKind::Grid(Box::new(surface)) });
        Ok(())
    })
}

/// Releases a surface; NULL is a no-op.
///
/// # Safety
/// `surface` must be NULL or a pointer from an `mf_surface_new_*` function, not yet freed and not
/// in use by another thread.
#[no_mangle]
pub unsafe extern "C" fn mf_surface_free(surface: *mut mf_surface) {
    free_handle(surface);
}

/// Runs `body` with the surface as a [`MeanSurface`] (the callbacks get `user_data`).
pub(crate) fn with_surface<R>(surface: &mf_surface, user_data: *mut c_void, body: impl SurfaceVisitor<Output = R>) -> R {
    match &surface.inner {
        SurfaceKind::Sphere(s) => body.visit(s),
        SurfaceKind::Mesh(m) => body.visit(m.as_ref()),
        SurfaceKind::Grid(g) => body.visit(g.as_ref()),
        SurfaceKind::Callbacks(c) => body.visit(&CallbackSurface::new(*c, user_data)),
    }
}

/// A computation generic over the surface kind (Rust closures cannot be generic).
pub(crate) trait SurfaceVisitor {
    type Output;
    fn visit<S: MeanSurface>(self, surface: &S) -> Self::Output;
}

struct EvalPoint(DVec3);

impl SurfaceVisitor for EvalPoint {
    type Output = Result<SurfacePoint>;
    fn visit<S: MeanSurface>(self, surface: &S) -> Result<SurfacePoint> {
        surface.point(self.0)
    }
}

/// The surface at `p`: its signed distance, frame normal and tangent (`user_data` goes to the
/// callbacks of a callback surface). Hosts use it for queries of their own, e.g. the mean of a
/// GPIS realization.
///
/// # Safety
/// Pointers must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mf_surface_eval(surface: *const mf_surface, user_data: *mut c_void, p: mf_vec3, out_point: *mut mf_surface_point) -> mf_status {
    boundary(|| {
        let s = arg(surface, "surface")?;
        let p = DVec3::from(p);
        if !p.is_finite() {
            return Err(invalid(format!("p must be finite, got {p}")));
        }
        let slot = out(out_point, "out_point")?;
        let point = with_surface(s, user_data, EvalPoint(p))?.validated(p)?;
        *slot = point.into();
        Ok(())
    })
}

/// The surface's bounding box (of the mean surface and its interior; infinite components when
/// unbounded).
///
/// # Safety
/// Pointers must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mf_surface_bounding_box(surface: *const mf_surface, out_min: *mut mf_vec3, out_max: *mut mf_vec3) -> mf_status {
    boundary(|| {
        let s = arg(surface, "surface")?;
        let (min_slot, max_slot) = (out(out_min, "out_min")?, out(out_max, "out_max")?);
        let b = match &s.inner {
            SurfaceKind::Sphere(x) => x.bounding_box(),
            SurfaceKind::Mesh(x) => x.bounding_box(),
            SurfaceKind::Grid(x) => x.bounding_box(),
            SurfaceKind::Callbacks(c) => c.bounds,
        };
        *min_slot = b.min.into();
        *max_slot = b.max.into();
        Ok(())
    })
}

struct BuildEnclosure {
    level: f64,
    cell: f64,
}

impl SurfaceVisitor for BuildEnclosure {
    type Output = Result<Enclosure>;
    fn visit<S: MeanSurface>(self, surface: &S) -> Result<Enclosure> {
        enclosure(surface, self.level, self.cell)
    }
}

/// A closed triangle mesh enclosing the region `f < level` of a surface (e.g. the level
/// `mf_medium_shell_top` of a medium): the boundary a host gives its ray tracer so that rays find
/// the medium without marching the signed distance. Conservative (the whole region is inside,
/// also after rounding the vertices to `float`), watertight, outward-facing, free of
/// self-intersections. With `cell_size` 0 and a mesh surface (`level > 0`): the mesh itself with
/// its vertices moved out along their normals, as many triangles, within about `level / cos θ`
/// of the level set (θ: the largest angle between a vertex normal and its faces), when that
/// verifies (clearance from every face, no faces crossing, winding once around the mesh).
/// Otherwise made of grid cells of about `cell_size` (0: 1/128 of the surface's largest extent,
/// or 1/8 of a larger `level`; at most 512 cells along an axis, at least 1e5 ulps of the largest
/// coordinate and 1e-53), within one cell diagonal of the level set (L of them for an SDF grid
/// whose interpolation is L-Lipschitz).
/// Needs a surface with a finite bounding box. Its exit level ([`mf_enclosure_exit_level`]) lets
/// tracking calls find the ray's exit themselves (`mf_track_query::exit_level`).
pub struct mf_enclosure {
    positions: Vec<f64>,
    indices: Vec<u32>,
    exit_level: f64,
}

/// Builds the enclosure of `f < level` (see [`mf_enclosure`]); `user_data` goes to the callbacks
/// of a callback surface. A mesh's own enclosure is checked on the threads its surface was built
/// with ([`mf_surface_new_mesh`]). Read it with [`mf_enclosure_mesh`], release it with
/// [`mf_enclosure_free`].
///
/// # Safety
/// Pointers must be NULL or valid; the callbacks must be safe to call with `user_data`.
#[no_mangle]
pub unsafe extern "C" fn mf_surface_enclosure(
    surface: *const mf_surface,
    user_data: *mut c_void,
    level: f64,
    cell_size: f64,
    out_enclosure: *mut *mut mf_enclosure,
) -> mf_status {
    boundary(|| {
        let s = arg(surface, "surface")?;
        let slot = out(out_enclosure, "out_enclosure")?;
        let e = with_surface(s, user_data, BuildEnclosure { level, cell: cell_size })?;
        let positions = e.positions.iter().flat_map(|p| p.to_array()).collect();
        let indices = e.triangles.iter().flatten().copied().collect();
        *slot = into_handle(mf_enclosure { positions, indices, exit_level: e.exit_level });
        Ok(())
    })
}

/// The enclosure's triangles as an [`mf_mesh`] (no normals or uvs) whose arrays belong to the
/// enclosure and stay valid until [`mf_enclosure_free`].
///
/// # Safety
/// Pointers must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mf_enclosure_mesh(enclosure: *const mf_enclosure, out_mesh: *mut mf_mesh) -> mf_status {
    boundary(|| {
        let e = arg(enclosure, "enclosure")?;
        let slot = out(out_mesh, "out_mesh")?;
        *slot = mf_mesh {
            positions: e.positions.as_ptr(),
            vertex_count: e.positions.len() / 3,
            indices: e.indices.as_ptr(),
            triangle_count: e.indices.len() / 3,
            normals: std::ptr::null(),
            uvs: std::ptr::null(),
        };
        Ok(())
    })
}

/// A level of `f` above which a point lies outside the enclosure: no point it encloses exceeds
/// it, nor any point within `float` rounding of it (the vertices as a host copies them, a ray's
/// origin). Give it as [`mf_track_query`]`::exit_level` to let the tracking calls end at the
/// ray's exit from the enclosure.
///
/// # Safety
/// Pointers must be NULL or valid.
///
/// [`mf_track_query`]: crate::track::mf_track_query
#[no_mangle]
pub unsafe extern "C" fn mf_enclosure_exit_level(enclosure: *const mf_enclosure, out_level: *mut f64) -> mf_status {
    boundary(|| {
        let e = arg(enclosure, "enclosure")?;
        *out(out_level, "out_level")? = e.exit_level;
        Ok(())
    })
}

/// Releases an enclosure; NULL is a no-op.
///
/// # Safety
/// `enclosure` must be NULL or from [`mf_surface_enclosure`], not yet freed.
#[no_mangle]
pub unsafe extern "C" fn mf_enclosure_free(enclosure: *mut mf_enclosure) {
    free_handle(enclosure);
}
