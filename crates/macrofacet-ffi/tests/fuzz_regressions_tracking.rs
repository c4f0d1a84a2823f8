//! Regression tests for what the `tracking`, `fields` and `ndf` fuzz targets found (issue 9,
//! `fuzz/fuzz_targets/`): each one the exact case of a crash artifact, reduced.

mod common;

use common::last_error;
use macrofacet_ffi::*;
use std::ptr;

/// The regular tetrahedron with vertices `(±s, ±s, ±s)` (an even number of minus signs).
fn tetrahedron(s: f64) -> (Vec<f64>, Vec<u32>) {
    let positions = vec![s, s, s, s, -s, -s, -s, s, -s, -s, -s, s];
    let indices = vec![0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2];
    (positions, indices)
}

/// The regular octahedron with vertices `±s` on the axes, in the order +x, −x, +y, −y, +z, −z.
fn octahedron(s: f64) -> (Vec<f64>, Vec<u32>) {
    let positions = vec![s, 0.0, 0.0, -s, 0.0, 0.0, 0.0, s, 0.0, 0.0, -s, 0.0, 0.0, 0.0, s, 0.0, 0.0, -s];
    let indices = vec![0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5];
    (positions, indices)
}

/// `mf_surface_new_mesh` on flat positions (and optional vertex normals and uvs) with triangle
/// indices: its status and surface.
fn new_mesh(positions: &[f64], indices: &[u32], normals: Option<&[f64]>, uvs: Option<&[f64]>) -> (mf_status, *mut mf_surface) {
    let or_null = |v: Option<&[f64]>| v.map_or(ptr::null(), <[f64]>::as_ptr);
    let mesh = mf_mesh { positions: positions.as_ptr(), vertex_count: positions.len() / 3, indices: indices.as_ptr(), triangle_count: indices.len() / 3, normals: or_null(normals), uvs: or_null(uvs) };
    let mut surface = ptr::null_mut();
    let status = unsafe { mf_surface_new_mesh(&mesh, 1, f64::INFINITY, &mut surface) };
    (status, surface)
}

/// A mesh surface that must be accepted.
fn accepted_mesh(positions: &[f64], indices: &[u32], normals: Option<&[f64]>) -> *mut mf_surface {
    let (status, surface) = new_mesh(positions, indices, normals, None);
    assert_eq!(status, mf_status::MF_OK, "{}", last_error());
    surface
}

/// `mf_surface_eval` at `p`: its status and point.
fn eval(surface: *const mf_surface, p: mf_vec3) -> (mf_status, mf_surface_point) {
    let zero = mf_vec3 { x: 0.0, y: 0.0, z: 0.0 };
    let mut point = mf_surface_point { f: 0.0, normal: zero, tangent: zero, u: 0.0, v: 0.0 };
    let status = unsafe { mf_surface_eval(surface, ptr::null_mut(), p, &mut point) };
    (status, point)
}

fn length(v: mf_vec3) -> f64 {
    (v.x * v.x + v.y * v.y + v.z * v.z).sqrt()
}

/// `fuzz/artifacts/tracking/crash-21498556eb8466047680f6176e4131c1c7fd8ce1` (a tetrahedron of
/// half-width 1e300), and the sweep of half-widths around it. Two failures:
/// - from 1e103 on, `mf_surface_new_mesh` panics (index 4294967295 out of bounds in
///   `src/surface/mesh/grid.rs` `CellGrid::build`: the cell size is the `cbrt` of the extents'
///   product, which overflows to inf, so block centres are NaN, the hierarchy finds no triangle
///   and its `u32::MAX` sentinel seeds the next search): MF_ERROR_INTERNAL;
/// - from 1e77 to 1e102 the mesh is accepted but `mf_surface_eval` at its centre answers
///   `f = +s` with normal (-1, 0, 0) instead of `-s/√3` (a product of squared lengths, ~s⁴,
///   overflows in the inside/outside decision): a wrong number with MF_OK.
///
/// A mesh whose size the library cannot handle must be refused with MF_ERROR_INVALID_ARGUMENT
/// and a reason; one it accepts must answer right.
#[test]
fn huge_mesh_is_refused_or_answers_right() {
    for s in [1.0, 1e50, 1e76, 1e77, 1e100, 1e102, 1e103, 1e150, 1e300] {
        let (positions, indices) = tetrahedron(s);
        let (status, surface) = new_mesh(&positions, &indices, None, None);
        assert!(status == mf_status::MF_OK || status == mf_status::MF_ERROR_INVALID_ARGUMENT, "half-width {s:e}: {status:?}");
        if status == mf_status::MF_OK {
            let zero = mf_vec3 { x: 0.0, y: 0.0, z: 0.0 };
            let (status, point) = eval(surface, zero);
            assert_eq!(status, mf_status::MF_OK, "half-width {s:e}");
            let expected = -s / 3f64.sqrt();
            assert!((point.f - expected).abs() <= 1e-9 * s, "half-width {s:e}: f at the centre {} (expected {expected})", point.f);
            unsafe { mf_surface_free(surface) };
        }
    }
}

/// A host surface that answers `f = NaN` (a unit normal) everywhere.
unsafe extern "C" fn nan_point(_: *mut std::ffi::c_void, _: mf_vec3, out: *mut mf_surface_point) -> i32 {
    let z = mf_vec3 { x: 0.0, y: 0.0, z: 1.0 };
    unsafe { *out = mf_surface_point { f: f64::NAN, normal: z, tangent: mf_vec3 { x: 1.0, y: 0.0, z: 0.0 }, u: 0.0, v: 0.0 } };
    0
}

/// A host sphere of radius 1 whose normal has length 2.
unsafe extern "C" fn long_normal_point(_: *mut std::ffi::c_void, p: mf_vec3, out: *mut mf_surface_point) -> i32 {
    let r = length(p);
    let n = mf_vec3 { x: 2.0 * p.x / r, y: 2.0 * p.y / r, z: 2.0 * p.z / r };
    unsafe { *out = mf_surface_point { f: r - 1.0, normal: n, tangent: mf_vec3 { x: 0.0, y: 0.0, z: 0.0 }, u: 0.0, v: 0.0 } };
    0
}

/// `fuzz/artifacts/tracking/crash-19d453b9d3bbb4d3eafba5a26721a5d25b4fcb0a`: a callback
/// surface's answer that the tracking calls refuse (NaN `f`, a normal of length 2: "the mean
/// surface at p returned ...: f must not be NaN, the normal must be unit") is passed on by
/// `mf_surface_eval` with MF_OK (`src/ffi/surface.rs`: `EvalPoint` returns `surface.point(p)`
/// unchecked; the check lives in `Tracker::checked`), and `mf_surface_enclosure` builds from it.
/// NaN is never a valid MF_OK output: both must fail with MF_ERROR_INVALID_ARGUMENT and write
/// nothing, as the tracking calls do.
#[test]
fn surface_eval_and_enclosure_refuse_what_tracking_refuses() {
    for (name, point) in [("NaN f", nan_point as unsafe extern "C" fn(_, _, _) -> _), ("normal of length 2", long_normal_point)] {
        let surface = callback_surface(point, MF_SURFACE_GENERAL, mf_vec3 { x: -1.0, y: -1.0, z: -1.0 }, mf_vec3 { x: 1.0, y: 1.0, z: 1.0 });
        let sentinel = mf_vec3 { x: -7.0, y: -7.0, z: -7.0 };
        let mut out = mf_surface_point { f: -7.0, normal: sentinel, tangent: sentinel, u: -7.0, v: -7.0 };
        let status = unsafe { mf_surface_eval(surface, ptr::null_mut(), mf_vec3 { x: 0.5, y: 0.25, z: 2.0 }, &mut out) };
        assert_eq!(status, mf_status::MF_ERROR_INVALID_ARGUMENT, "{name}: mf_surface_eval gave {out:?}");
        assert_eq!(out.f, -7.0, "{name}: written on failure");
        let mut enclosure = ptr::null_mut();
        let status = unsafe { mf_surface_enclosure(surface, ptr::null_mut(), 0.1, 0.25, &mut enclosure) };
        assert_eq!(status, mf_status::MF_ERROR_INVALID_ARGUMENT, "{name}: mf_surface_enclosure");
        assert!(enclosure.is_null());
        unsafe { mf_surface_free(surface) };
    }
}

/// `fuzz/artifacts/tracking/crash-317795d42a035b8f72fed485d81f5c018b38d567`: a mesh of two
/// zero-area triangles (all three vertices at the origin) is accepted by `mf_surface_new_mesh`,
/// and `mf_surface_eval` then answers MF_OK with the normal (0, 0, 0), which no frame takes
/// (the tracking calls refuse it mid-walk); at the vertex itself (0, 0, 0), and on the segment of
/// collinear vertices at (0.5, 0, 0), and on a flat mesh (triangles with area, no volume). A mesh without area
/// must be refused when it is created, with the reason (or answer unit normals).
#[test]
fn mesh_without_area_is_refused_or_has_unit_normals() {
    let two_sided: Vec<u32> = vec![0, 1, 2, 0, 2, 1];
    let cases: [(&str, Vec<f64>, Vec<u32>); 3] = [
        ("coincident", vec![0.0; 9], two_sided.clone()),
        ("collinear", vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 2.0, 0.0, 0.0], two_sided),
        // crash-5e2f7b9998975b55da7d43942b4e1411ae281316: a flat "tetrahedron" (z = 0), eval at
        // (1e-320, 0, 0).
        ("flat", vec![0.0, 0.0, 0.0, -2.0, 0.0, 0.0, -2.0, 0.0, 0.0, 0.0, -1.0, 0.0], vec![0, 1, 2, 0, 2, 3, 0, 3, 1, 1, 3, 2]),
    ];
    for (name, positions, indices) in cases {
        let (status, surface) = new_mesh(&positions, &indices, None, None);
        if status == mf_status::MF_ERROR_INVALID_ARGUMENT {
            continue;
        }
        assert_eq!(status, mf_status::MF_OK, "{name}");
        for p in [mf_vec3 { x: 0.3, y: 0.2, z: 0.1 }, mf_vec3 { x: -1.0, y: 0.0, z: 0.0 }, mf_vec3 { x: 0.5, y: 0.0, z: 0.0 }, mf_vec3 { x: 0.0, y: 0.0, z: 0.0 }, mf_vec3 { x: 1e-320, y: 0.0, z: 0.0 }] {
            let (status, point) = eval(surface, p);
            let n = point.normal;
            let len = length(n);
            assert!(status != mf_status::MF_OK || (len - 1.0).abs() <= 1e-6 && !point.f.is_nan(), "{name} at {p:?}: {point:?}");
        }
        unsafe { mf_surface_free(surface) };
    }
}

/// `fuzz/artifacts/fields/crash-c049bbc5d791283fe3bffedcb0ad4bee0a9cca62`: a sphere of radius
/// 5.69 centred 4e-163 above the origin, `mf_surface_eval` at the origin: the normal had length
/// 0.9999955 (|p − c|² underflows). And `fuzz/artifacts/tracking/crash-fc4b700986975a649f7809731b004679d4581201`:
/// a mesh 2.9e-320 wide (one triangle, welded closed) overflowed the acceleration grid's cell
/// count (a panic, MF_ERROR_INTERNAL); meshes narrower than the σ range are refused.
#[test]
fn tiny_offsets_and_tiny_meshes() {
    let mut sphere = ptr::null_mut();
    let center = mf_vec3 { x: 0.0, y: 0.0, z: 3.984366405781637e-163 };
    let pole = mf_vec3 { x: 0.0, y: 0.0, z: 1.0 };
    assert_eq!(unsafe { mf_surface_new_sphere(center, 5.688840528388324, false, pole, &mut sphere) }, mf_status::MF_OK);
    let zero = mf_vec3 { x: 0.0, y: 0.0, z: 0.0 };
    let (status, point) = eval(sphere, zero);
    assert_eq!(status, mf_status::MF_OK);
    let n = point.normal;
    assert!((length(n) - 1.0).abs() <= 1e-15, "{point:?}");
    assert_eq!((n.x, n.y, n.z), (0.0, 0.0, -1.0), "{point:?}");
    unsafe { mf_surface_free(sphere) };

    let positions = [0.0, 2.884e-320, 0.0, 0.0, 2.884e-320, 0.0, 0.0, 0.0, 2.884e-320];
    let normals = [0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0];
    let uvs = [0.0; 6];
    let (status, surface) = new_mesh(&positions, &[0, 1, 2], Some(&normals), Some(&uvs));
    assert_eq!(status, mf_status::MF_ERROR_INVALID_ARGUMENT);
    assert!(surface.is_null());
    let message = last_error();
    assert!(message.contains("smallest length"), "{message}");
}

/// `fuzz/artifacts/tracking/crash-7eeb41be00481e1a538e452f8520de7af17fa2b5`: an octahedron of
/// half-width 1.7e-161 (one vertex moved out to (0, 6.47, 6.47), one duplicated): its face
/// normals came from cross products of edges whose product is subnormal, and
/// `mf_surface_eval` at (8.9e-161, 8.9e-161, 8.9e-161) answered MF_OK with a normal of length
/// 1.0000705. Every normal must be unit to rounding, here and over a sweep of tiny scales.
#[test]
fn tiny_mesh_has_unit_face_normals() {
    // The artifact's mesh at scale `s`: five vertices within `s` of the origin, one at 6.47.
    let mesh = |s: f64| [-s, 0.0, 0.0, -s, 0.0, 0.0, 0.0, s, 0.0, 0.0, -s, 0.0, 0.0, 6.470588235294117, 6.470588235294117, 0.0, 0.0, -s];
    let (_, indices) = octahedron(1.0);
    for s in [1.724222298951975e-161, 1e-150, 3e-155, 1e-200, 1e-250, 1e-300] {
        let surface = accepted_mesh(&mesh(s), &indices, None);
        for q in [[5.176470588235293, 5.176470588235293, 5.176470588235293], [0.3, 0.2, 0.1], [0.01, -0.5, -0.9], [2.0, -1.0, 0.5]] {
            let (status, point) = eval(surface, mf_vec3 { x: q[0] * s, y: q[1] * s, z: q[2] * s });
            assert_eq!(status, mf_status::MF_OK, "{}", last_error());
            assert!((length(point.normal) - 1.0).abs() <= 1e-12, "scale {s:e} at {q:?}: {point:?}");
        }
        unsafe { mf_surface_free(surface) };
    }
}

/// `fuzz/artifacts/tracking/crash-f608ee00e91797708ef8fd1375c9fa83fb734e0d`: far from a
/// surface, where `|p − closest|²` overflows (|p| ~ 1e304; the tetrahedron of that artifact had
/// half-width 5.4e51), `mf_surface_eval` answers MF_OK with the normal (0, 0, 0) (`f = +inf` is
/// the overflow issue 9 accepts; a zero normal is no frame). Checked for a mesh and a sphere:
/// MF_OK must come with a unit normal (or the point be refused as out of range).
#[test]
fn far_point_has_a_unit_normal() {
    let (positions, indices) = tetrahedron(1.0);
    let mesh_surface = accepted_mesh(&positions, &indices, None);
    let mut sphere_surface = ptr::null_mut();
    let zero = mf_vec3 { x: 0.0, y: 0.0, z: 0.0 };
    assert_eq!(unsafe { mf_surface_new_sphere(zero, 1.0, false, mf_vec3 { x: 0.0, y: 0.0, z: 1.0 }, &mut sphere_surface) }, mf_status::MF_OK);
    for (name, surface) in [("mesh", mesh_surface), ("sphere", sphere_surface)] {
        for p in [mf_vec3 { x: 1.0650001015113206e304, y: 1e-320, z: 0.0 }, mf_vec3 { x: 1e200, y: 1e200, z: 0.0 }] {
            let (status, point) = eval(surface, p);
            let n = point.normal;
            let len = length(n);
            assert!(status != mf_status::MF_OK || (len - 1.0).abs() <= 1e-6 && !point.f.is_nan(), "{name} at {p:?}: {point:?}");
        }
    }
    unsafe {
        mf_surface_free(mesh_surface);
        mf_surface_free(sphere_surface);
    }
}

/// `fuzz/artifacts/tracking/crash-e78f2d4e087aab1dfd4f9cef01c5806e0903acef`: a tetrahedron
/// (half-width 5.6e50) with finite texture coordinates, one of them `v = -1e308`, is accepted,
/// and `mf_surface_eval` at its centre answers MF_OK with the tangent (inf, -inf, NaN): `dp/du`
/// overflows. (The tracking calls refuse such a point mid-walk.) The mesh must be refused, or
/// the tangent be finite (any fallback a zero-area uv triangle gets).
#[test]
fn mesh_uvs_never_give_a_non_finite_tangent() {
    let s = 5.645309114862115e50;
    let (positions, indices) = tetrahedron(s);
    let uvs = [0.9999999999991047, -9.999999999997382e307, 0.035162057122917534, 0.5, 1.3233858453531866e-13, 0.0, 0.0, 0.0];
    let (status, surface) = new_mesh(&positions, &indices, None, Some(&uvs));
    if status == mf_status::MF_ERROR_INVALID_ARGUMENT {
        return;
    }
    assert_eq!(status, mf_status::MF_OK);
    let zero = mf_vec3 { x: 0.0, y: 0.0, z: 0.0 };
    let (status, point) = eval(surface, zero);
    let t = point.tangent;
    assert!(status != mf_status::MF_OK || [t.x, t.y, t.z, point.u, point.v].iter().all(|x| x.is_finite()), "{point:?}");
    unsafe { mf_surface_free(surface) };
}

/// A medium from named float and string parameters.
fn medium(floats: &[(&str, f64)], strings: &[(&str, &str)]) -> *mut mf_medium {
    let mut params = ptr::null_mut();
    let mut medium = ptr::null_mut();
    unsafe {
        assert_eq!(mf_params_new(&mut params), mf_status::MF_OK);
        for (name, x) in floats {
            let name = std::ffi::CString::new(*name).unwrap();
            assert_eq!(mf_params_set_float(params, name.as_ptr(), *x), mf_status::MF_OK);
        }
        for (name, s) in strings {
            let (name, s) = (std::ffi::CString::new(*name).unwrap(), std::ffi::CString::new(*s).unwrap());
            assert_eq!(mf_params_set_string(params, name.as_ptr(), s.as_ptr()), mf_status::MF_OK);
        }
        assert_eq!(mf_medium_new(params, &mut medium), mf_status::MF_OK);
        mf_params_free(params);
    }
    medium
}

/// `fuzz/artifacts/tracking/slow-unit-b65a9cd5d2ed8e5949570c3a85ed21faa8690080` (24 s under
/// the fuzzer): GGX at α = 1e6 (the domain's top), σ = 1e50, around a sphere of radius 986; a
/// ray from inside the sphere along +z through its centre to +inf. T = 1 is right (GGX has
/// Λ = 0 along the normal, and the density is ~4e-51 per unit length), but d·n turns from −1 to
/// +1 at the centre, so the first segment's `S_up` covers grazing frames (~α) while the true
/// `σ(d)` is 1 or 0: it took 1,580,394 tentative collisions, later the tentative cap's error.
/// Such segments are now shortened to a few expected tentative collisions
/// (`src/tracking.rs`, `WIDE_RANGE_COLLISIONS`). Counted, not timed.
#[test]
fn rough_medium_around_a_sphere_has_a_bounded_cost() {
    let m = medium(&[("variance", 1e100), ("alpha", 1e6)], &[("distribution", "ggx"), ("material", "Ag")]);
    let mut sphere = ptr::null_mut();
    let zero = mf_vec3 { x: 0.0, y: 0.0, z: 0.0 };
    let pole = mf_vec3 { x: 0.8802167343846036, y: 0.0000006623900790494924, z: 0.4745719128950485 };
    assert_eq!(unsafe { mf_surface_new_sphere(zero, 986.18349699642, false, pole, &mut sphere) }, mf_status::MF_OK);
    let q = mf_track_query { origin: mf_vec3 { x: -0.0, y: 0.0, z: -5.39063829912263 }, d: mf_vec3 { x: 0.0, y: 0.0, z: 1.0 }, t_max: f64::INFINITY, seed: 0, exit_level: 0.0, survival: 0.0, hint: 0 };
    let mut t = mf_transmittance { transmittance: -1.0, t: 0.0, stats: mf_track_stats::default() };
    let status = unsafe { mf_track_transmittance(m, sphere, ptr::null(), ptr::null_mut(), &q, &mut t) };
    assert_eq!(status, mf_status::MF_OK);
    // The optical depth is ~2e-50. One ratio-tracking estimate is not that close: each tentative
    // collision scales it by 1 − σ_t/μ, and here the majorant's grazing area (~α) exceeds σ_t up
    // to ~1e5-fold, so each costs at most ~1e-5 (0.9999923 after 11 of them with seed 0).
    assert!(t.transmittance <= 1.0 && t.transmittance > 1.0 - 1e-4, "{t:?}");
    // 15 surface queries and 11 tentative collisions (1.6e6 before the fix).
    assert!(t.stats.surface_queries <= 100, "{t:?}");
    unsafe {
        mf_surface_free(sphere);
        mf_medium_free(m);
    }
}

/// A host sphere of radius `RADIUS` around the origin that fails (code 1) from its
/// `MAX_CALLS + 1`-th call on: a bound on the work of one tracking call that is counted, not
/// timed.
const RADIUS: f64 = 1000.0000000010001;
const MAX_CALLS: u64 = 1_000_000;

unsafe extern "C" fn counted_sphere(user_data: *mut std::ffi::c_void, p: mf_vec3, out: *mut mf_surface_point) -> i32 {
    let calls = unsafe { &mut *(user_data as *mut u64) };
    *calls += 1;
    if *calls > MAX_CALLS {
        return 1;
    }
    let r = length(p);
    let n = if r > 0.0 { mf_vec3 { x: p.x / r, y: p.y / r, z: p.z / r } } else { mf_vec3 { x: 0.0, y: 0.0, z: 1.0 } };
    unsafe { *out = mf_surface_point { f: r - RADIUS, normal: n, tangent: mf_vec3 { x: 1.0, y: 0.0, z: 0.0 }, u: 0.0, v: 0.0 } };
    0
}

/// `fuzz/artifacts/tracking/crash-2d53ff10cd0b27843794feff88a99f4879f8e213` (a hang: stopped by
/// hand after 6 minutes in the fuzzer, inside `Tracker::sample_free_flight`'s loop over tentative
/// collisions, `src/tracking.rs` ~line 444, calling the surface): σ = 1e-50, GGX α = 1e-6
/// (`lengthscale` 1.414e-44), an honest convex callback sphere of radius 1000 (1e53 σ), a ray
/// from its centre along +y to +inf, seed 49730685199106. Suspected: ~1e53 σ below the surface
/// the density is ~1e103 per unit length, the inverted step `ds` underflows against `s` (or
/// `σ_t` is 0 for a ray along the normal of a mirror-like GGX while the majorant is not), so
/// the loop over tentative collisions neither advances nor ends; it has no bound of its own
/// (MAX_SEGMENTS bounds segments only). A call must end — with an answer or a clear error —
/// within a bounded number of surface queries (here 1e6).
#[test]
fn free_flight_from_deep_inside_a_thin_medium_ends() {
    let m = medium(&[("sigma", 1e-50), ("lengthscale", 1.4142135623730952e-44)], &[("distribution", "ggx")]);
    let surface = callback_surface(counted_sphere, MF_SURFACE_CONVEX, mf_vec3 { x: -RADIUS, y: -RADIUS, z: -RADIUS }, mf_vec3 { x: RADIUS, y: RADIUS, z: RADIUS });
    let q = mf_track_query { origin: mf_vec3 { x: 0.0, y: 0.0, z: 0.0 }, d: mf_vec3 { x: -0.0, y: 1.0, z: -1e-300 }, t_max: f64::INFINITY, seed: 49730685199106, exit_level: 0.0, survival: 0.0, hint: 0 };
    let mut calls = 0u64;
    let mut c = std::mem::MaybeUninit::<mf_collision>::uninit();
    let status = unsafe { mf_track_free_flight(m, surface, ptr::null(), &mut calls as *mut u64 as *mut std::ffi::c_void, &q, c.as_mut_ptr()) };
    assert!(status != mf_status::MF_ERROR_CALLBACK, "still tracking after {MAX_CALLS} surface queries");
    unsafe {
        mf_surface_free(surface);
        mf_medium_free(m);
    }
}

/// `fuzz/artifacts/tracking/crash-5fbb2376c5aedc8642244a121e9091e4e9b4b8a1`: the enclosure of
/// a tetrahedron 2000 wide at the level 1e47 (σ = 1e50) had a vertex inside the region, because
/// `f` at that vertex, 1.5e47 away, came out negative: that far, every feature of the mesh is at
/// the same rounded distance and the pseudo-normal test picks a face facing away. Outside the
/// mesh's bounding box `f` is now positive.
#[test]
fn mesh_far_away_is_outside() {
    let (positions, indices) = tetrahedron(1000.0000000010001);
    let surface = accepted_mesh(&positions, &indices, None);
    for p in [mf_vec3 { x: -1.0316227766019487e47, y: -1.0316227766019487e47, z: 1.1928851295354665e45 }, mf_vec3 { x: 1e20, y: 0.0, z: 0.0 }, mf_vec3 { x: 0.0, y: -3e30, z: 2e30 }] {
        let (status, point) = eval(surface, p);
        assert_eq!(status, mf_status::MF_OK);
        assert!(point.f > 0.0, "f({p:?}) = {}", point.f);
    }
    unsafe { mf_surface_free(surface) };
}

/// A convex callback sphere of radius 1 whose answers carry an infinite tangent from the second
/// call on (counted in `user_data`).
unsafe extern "C" fn sphere_with_bad_tangent(user_data: *mut std::ffi::c_void, p: mf_vec3, out: *mut mf_surface_point) -> i32 {
    let calls = unsafe { &mut *(user_data as *mut u64) };
    *calls += 1;
    let r = length(p);
    let tangent = if *calls >= 2 { f64::INFINITY } else { 0.0 };
    unsafe { *out = mf_surface_point { f: r - 1.0, normal: mf_vec3 { x: p.x / r, y: p.y / r, z: p.z / r }, tangent: mf_vec3 { x: tangent, y: 1.0, z: 0.0 }, u: 0.0, v: 0.0 } };
    0
}

/// `fuzz/artifacts/fields/crash-b83316f9192f94465db3bfcaae8373caa0a90f88`: a convex callback
/// surface answers the end of a segment bound with an infinite tangent; the tracker used that end
/// point unchecked and went on for 6 callback calls (the rule is an error within 4 of a visible
/// lie). The end point is now checked with the bound.
#[test]
fn segment_end_from_a_callback_is_checked() {
    let m = medium(&[("sigma", 0.01), ("alpha", 0.3)], &[("distribution", "beckmann")]);
    let surface = callback_surface(sphere_with_bad_tangent, MF_SURFACE_CONVEX, mf_vec3 { x: -1.0, y: -1.0, z: -1.0 }, mf_vec3 { x: 1.0, y: 1.0, z: 1.0 });
    let q = mf_track_query { origin: mf_vec3 { x: 0.0, y: 0.0, z: 1.02 }, d: mf_vec3 { x: 0.0, y: 0.0, z: -1.0 }, t_max: f64::INFINITY, seed: 1, exit_level: 0.0, survival: 0.0, hint: 0 };
    let mut calls = 0u64;
    let mut c = std::mem::MaybeUninit::<mf_collision>::uninit();
    let status = unsafe { mf_track_free_flight(m, surface, ptr::null(), &mut calls as *mut u64 as *mut std::ffi::c_void, &q, c.as_mut_ptr()) };
    assert_eq!(status, mf_status::MF_ERROR_INVALID_ARGUMENT);
    assert!(calls <= 2, "{calls} callback calls");
    assert!(last_error().contains("tangent"), "{}", last_error());
    unsafe {
        mf_surface_free(surface);
        mf_medium_free(m);
    }
}

/// The plane `n·p − offset` of `fuzz/artifacts/tracking/crash-9100370be8f595f2f2f94225b606f58d0e23535b`.
const PLANE_NORMAL: [f64; 3] = [0.12471758887363776, -0.0030571111562215543, 0.9921875715291564];
const PLANE_OFFSET: f64 = -1.7362059233297435e-45;

unsafe extern "C" fn tilted_plane(_: *mut std::ffi::c_void, p: mf_vec3, out: *mut mf_surface_point) -> i32 {
    let [x, y, z] = PLANE_NORMAL;
    unsafe { *out = mf_surface_point { f: x * p.x + y * p.y + z * p.z - PLANE_OFFSET, normal: mf_vec3 { x, y, z }, tangent: mf_vec3 { x: 1.0, y: 0.0, z: 0.0 }, u: 0.0, v: 0.0 } };
    0
}

/// `fuzz/artifacts/tracking/crash-9100370be8f595f2f2f94225b606f58d0e23535b`: σ = 1e-50, GGX
/// α = 1e6, an honest plane (a concave callback), a ray 100 σ above it descending at d·n = −1e-8:
/// the tentative collisions lie 1e-40 along the ray, where rounding the coordinates moves f by
/// 1e-6 σ, and the plane's exact majorant was exceeded (1 violation in 92). The bounds of `f` now
/// include the rounding of the positions. Farther along the ray the rounding exceeds σ: there a
/// call may end with the tentative cap's error, naming the cause, but never answers MF_OK with a
/// broken majorant.
#[test]
fn plane_majorant_holds_at_rounded_positions() {
    let m = medium(&[("sigma", 1e-50), ("lengthscale", 1.4142135623730953e-56)], &[("distribution", "ggx")]);
    let surface = callback_surface(tilted_plane, MF_SURFACE_CONCAVE, mf_vec3 { x: f64::NEG_INFINITY, y: f64::NEG_INFINITY, z: f64::NEG_INFINITY }, mf_vec3 { x: f64::INFINITY, y: f64::INFINITY, z: f64::INFINITY });
    let origin = mf_vec3 { x: 2.917864118616786e-48, y: 7.315226577307254e-49, z: 6.7081289745737284e-49 };
    let d = mf_vec3 { x: 0.00019138411119676342, y: 0.9999953087410786, z: 0.003057101234345839 };
    let (mut violations, mut answered, mut refused) = (0, 0, 0);
    let mut tally = |status: mf_status, stats: Option<mf_track_stats>, seed: u64| {
        if status == mf_status::MF_OK {
            answered += 1;
            violations += stats.expect("stats of an answer").majorant_violations;
        } else {
            assert!(last_error().contains("rounding of the coordinates"), "seed {seed}: {}", last_error());
            refused += 1;
        }
    };
    for seed in (0..40).chain([8361610016553369471]) {
        let q = mf_track_query { origin, d, t_max: f64::INFINITY, seed, exit_level: 0.0, survival: 0.0, hint: 0 };
        let mut c = std::mem::MaybeUninit::<mf_collision>::uninit();
        let status = unsafe { mf_track_free_flight(m, surface, ptr::null(), ptr::null_mut(), &q, c.as_mut_ptr()) };
        tally(status, (status == mf_status::MF_OK).then(|| unsafe { c.assume_init() }.stats), seed);
        let mut t = mf_transmittance { transmittance: -1.0, t: 0.0, stats: mf_track_stats::default() };
        let status = unsafe { mf_track_transmittance(m, surface, ptr::null(), ptr::null_mut(), &q, &mut t) };
        tally(status, Some(t.stats), seed);
    }
    assert_eq!(violations, 0, "majorant violations over 41 seeds ({answered} answered, {refused} refused)");
    assert!(answered > 0, "{refused} refused");
    unsafe {
        mf_surface_free(surface);
        mf_medium_free(m);
    }
}

/// `fuzz/artifacts/fields/crash-1db97a14de404eb89d75bb528ad4094abe4dff09`: a degenerate mesh
/// 3e49 wide evaluated 1e300 away: every product of the closest-point test overflowed, no
/// triangle was found and the lookup of "none" panicked (MF_ERROR_INTERNAL). Far points now get
/// f = +inf and a unit normal.
#[test]
fn mesh_evaluated_beyond_overflow() {
    let s = 3.0193516770859723e49;
    let surface = accepted_mesh(&[0.0, s, 0.0, 0.0, s, 0.0, 0.0, 0.0, s], &[0, 1, 2], None);
    for p in [mf_vec3 { x: 1e300, y: 1e300, z: 1e300 }, mf_vec3 { x: -1e300, y: 0.0, z: 0.0 }, mf_vec3 { x: 0.0, y: -1e308, z: 1e308 }] {
        let (status, point) = eval(surface, p);
        assert_eq!(status, mf_status::MF_OK, "{p:?}: {}", last_error());
        let n = point.normal;
        assert!(point.f > 0.0 && (length(n) - 1.0).abs() < 1e-12, "{p:?}: {point:?}");
    }
    unsafe { mf_surface_free(surface) };
}

/// A plane `z = 0` whose normal comes back 1.00005 long (hosts compute in f32; the tracker takes
/// normals within 1e-4 of unit).
unsafe extern "C" fn long_normal_plane(_: *mut std::ffi::c_void, p: mf_vec3, out: *mut mf_surface_point) -> i32 {
    unsafe { *out = mf_surface_point { f: p.z, normal: mf_vec3 { x: 0.0, y: 0.0, z: 1.00005 }, tangent: mf_vec3 { x: 1.0, y: 0.0, z: 0.0 }, u: 0.0, v: 0.0 } };
    0
}

/// `fuzz/artifacts/tracking/crash-eaebd8d9f76ceea0c4ed99fc8f11113526121388`: a host normal
/// 1.00005 long is accepted, and the collision's frame handed it back as it came; the frame of
/// a collision is now unit. (With such a normal along the ray, a convex surface's bound also
/// came out as the unordered cosine range [-1, -1.00005], an error; it is clamped, then ordered.)
#[test]
fn collision_frame_is_unit() {
    let m = medium(&[("sigma", 0.01), ("alpha", 0.3)], &[("distribution", "beckmann")]);
    let surface = callback_surface(long_normal_plane, MF_SURFACE_CONVEX, mf_vec3 { x: f64::NEG_INFINITY, y: f64::NEG_INFINITY, z: f64::NEG_INFINITY }, mf_vec3 { x: f64::INFINITY, y: f64::INFINITY, z: 0.0 });
    let q = mf_track_query { origin: mf_vec3 { x: 0.0, y: 0.0, z: 0.05 }, d: mf_vec3 { x: 0.0, y: 0.0, z: -1.0 }, t_max: f64::INFINITY, seed: 3, exit_level: 0.0, survival: 0.0, hint: 0 };
    let mut c = std::mem::MaybeUninit::<mf_collision>::uninit();
    assert_eq!(unsafe { mf_track_free_flight(m, surface, ptr::null(), ptr::null_mut(), &q, c.as_mut_ptr()) }, mf_status::MF_OK, "{}", last_error());
    let c = unsafe { c.assume_init() };
    assert!(c.scattered, "{c:?}");
    let n = c.frame.normal;
    assert!((length(n) - 1.0).abs() <= 1e-15, "{c:?}");
    unsafe {
        mf_surface_free(surface);
        mf_medium_free(m);
    }
}

/// A host surface of `point` callbacks (no `bound`) with the given shape and box.
fn callback_surface(point: unsafe extern "C" fn(*mut std::ffi::c_void, mf_vec3, *mut mf_surface_point) -> i32, shape: u32, bounds_min: mf_vec3, bounds_max: mf_vec3) -> *mut mf_surface {
    let callbacks = mf_surface_callbacks { point: Some(point), bound: None, shape, bounds_min, bounds_max };
    let mut surface = ptr::null_mut();
    assert_eq!(unsafe { mf_surface_new_callbacks(&callbacks, &mut surface) }, mf_status::MF_OK);
    surface
}

/// Majorant violations of `mf_track_free_flight` and of `mf_track_transmittance` along one ray
/// over `seeds` (every call must answer MF_OK).
fn violations(m: *const mf_medium, surface: *const mf_surface, origin: mf_vec3, d: mf_vec3, t_max: f64, seeds: impl IntoIterator<Item = u64>) -> (u32, u32) {
    violations_of_calls(m, surface, origin, d, t_max, seeds, false)
}

/// [`violations`], with calls that fail (the tentative cap's error, where rounding leaves the
/// majorant too loose to finish) allowed when `errors_allowed`, and not counted.
fn violations_of_calls(m: *const mf_medium, surface: *const mf_surface, origin: mf_vec3, d: mf_vec3, t_max: f64, seeds: impl IntoIterator<Item = u64>, errors_allowed: bool) -> (u32, u32) {
    let (mut free_flight, mut transmittance) = (0, 0);
    for seed in seeds {
        let q = mf_track_query { origin, d, t_max, seed, exit_level: 0.0, survival: 0.0, hint: 0 };
        let mut c = std::mem::MaybeUninit::<mf_collision>::uninit();
        let status = unsafe { mf_track_free_flight(m, surface, ptr::null(), ptr::null_mut(), &q, c.as_mut_ptr()) };
        assert!(errors_allowed || status == mf_status::MF_OK, "{status:?}: {}", last_error());
        if status == mf_status::MF_OK {
            free_flight += unsafe { c.assume_init() }.stats.majorant_violations;
        }
        let mut t = mf_transmittance { transmittance: -1.0, t: 0.0, stats: mf_track_stats::default() };
        let status = unsafe { mf_track_transmittance(m, surface, ptr::null(), ptr::null_mut(), &q, &mut t) };
        assert!(errors_allowed || status == mf_status::MF_OK, "{status:?}: {}", last_error());
        if status == mf_status::MF_OK {
            transmittance += t.stats.majorant_violations;
        }
    }
    (free_flight, transmittance)
}

/// The vertices of `mf_surface_enclosure(surface, level, cell)` (which must answer MF_OK with
/// triangles), each with the `f` that `mf_surface_eval` answers there.
fn enclosure_vertices(surface: *const mf_surface, level: f64, cell: f64) -> Vec<([f64; 3], f64)> {
    let mut enclosure = ptr::null_mut();
    assert_eq!(unsafe { mf_surface_enclosure(surface, ptr::null_mut(), level, cell, &mut enclosure) }, mf_status::MF_OK, "{}", last_error());
    let mut mesh = std::mem::MaybeUninit::<mf_mesh>::uninit();
    assert_eq!(unsafe { mf_enclosure_mesh(enclosure, mesh.as_mut_ptr()) }, mf_status::MF_OK);
    let mesh = unsafe { mesh.assume_init() };
    assert!(mesh.triangle_count > 0);
    let vertices = unsafe { std::slice::from_raw_parts(mesh.positions, 3 * mesh.vertex_count) }
        .chunks_exact(3)
        .map(|v| {
            let (status, point) = eval(surface, mf_vec3 { x: v[0], y: v[1], z: v[2] });
            assert_eq!(status, mf_status::MF_OK);
            ([v[0], v[1], v[2]], point.f)
        })
        .collect();
    unsafe { mf_enclosure_free(enclosure) };
    vertices
}

/// `fuzz/artifacts/fields/crash-76e43ecab3d8a0691edf43c77d8aefb174925676`: gpss α = 1e-6,
/// σ = 1e50, a flipped sphere of radius 3e49 and a ray 1.6e147 from its centre at
/// d·n = 1.09e-5. There the projected area of the nearly smooth lobe is ~1e-58 and changes by
/// 2.2e-9 relative per ulp of d·n, which the segment's `S_up` (evaluated through acos and cos)
/// and `σ_t` compute apart: 1 majorant violation in 1 tentative collision. `S_up` and `S_lo` now
/// carry a relative margin for that rounding (`src/tracking.rs`, `AREA_ROUNDING`).
#[test]
fn grazing_smooth_lobe_majorant_holds() {
    let m = medium(&[("sigma", 1e50), ("alpha", 1e-6)], &[("distribution", "gpss"), ("material", "Cr")]);
    let mut sphere = ptr::null_mut();
    let zero = mf_vec3 { x: 0.0, y: 0.0, z: 0.0 };
    let pole = mf_vec3 { x: -0.4874571252713524, y: 0.722560278255522, z: -0.4901960784313677 };
    assert_eq!(unsafe { mf_surface_new_sphere(zero, 3.0000020598310863e49, true, pole, &mut sphere) }, mf_status::MF_OK);
    let origin = mf_vec3 { x: 40.0, y: -1.6489104643430374e147, z: 4.901960784313724 };
    let d = mf_vec3 { x: 0.7273426270154498, y: 1.0938525648383066e-5, z: 0.6862745098039216 };
    let (free_flight, transmittance) = violations(m, sphere, origin, d, f64::INFINITY, 0..64);
    assert_eq!(free_flight + transmittance, 0, "majorant violations over 64 seeds");
    unsafe {
        mf_surface_free(sphere);
        mf_medium_free(m);
    }
}

/// `fuzz/artifacts/tracking/crash-f92bbbb70f1ab04a562ada5de97959df00c1b6e5`: GGX at α = 1e6
/// (σ = 1e-50, lengthscale 1.4e-56), a flipped sphere of radius 2.2e-49 and a ray from 10 radii
/// out along the radius, so `d·n = −1` along the whole segment. One ulp of `d·n` below 1 in
/// magnitude is an angle of 2.1e-8 rad, where this lobe's projected area is already 1.1e-4
/// larger than along the normal: `σ_t` (its own rounding of `d·n`) exceeded the majorant at the
/// first tentative collision of every seed. The bounds now cover `d·n` rounded up to 8 ulps past
/// the segment's range (`src/tracking.rs`, `COS_ROUNDING`).
#[test]
fn rough_lobe_along_the_normal_majorant_holds() {
    let m = medium(&[("sigma", 1e-50), ("lengthscale", 1.4142135623730953e-56)], &[("distribution", "ggx")]);
    let mut sphere = ptr::null_mut();
    let zero = mf_vec3 { x: 0.0, y: 0.0, z: 0.0 };
    let pole = mf_vec3 { x: 0.09350315004139367, y: -1.0594914672242623e-16, z: -0.9956189838147607 };
    assert_eq!(unsafe { mf_surface_new_sphere(zero, 2.1878780977404597e-49, true, pole, &mut sphere) }, mf_status::MF_OK);
    let origin = mf_vec3 { x: 4.610608337288503e-56, y: -5.224316175345618e-71, z: -2.187878097740457e-48 };
    let d = mf_vec3 { x: 2.107344532887127e-8, y: -2.387848484363566e-23, z: -1.0000009999999997 };
    let (free_flight, transmittance) = violations(m, sphere, origin, d, 2.1878780977404594e-48, (0..64).chain([u64::MAX]));
    assert_eq!(free_flight + transmittance, 0, "majorant violations over 65 seeds");
    unsafe {
        mf_surface_free(sphere);
        mf_medium_free(m);
    }
}

/// `fuzz/artifacts/tracking/crash-d5d477e31881283f6ffd008660be24d4e683e9cb`: a 3×3×3 SDF grid
/// under a shearing `to_world`, whose interpolated `f` changes faster than distance (Lipschitz
/// constant above 1). `mf_surface_enclosure` decided cells with the bound of a signed distance
/// (`f` changes by at most half a cell diagonal from a cell's centre to its corners), dropped
/// cells of the region, and a vertex of the enclosure had `f` = 2.95e50 below the level 3e50.
/// The enclosure now scales that bound by the surface's Lipschitz constant
/// (`MeanSurface::lipschitz`).
#[test]
fn enclosure_of_a_steep_grid_contains_the_region() {
    let values: [f32; 27] = [
        0.70465285, 0.5457342, 0.70465285, 0.5457342, 0.33862746, 0.5457342, 0.70465285, 0.5457342, 0.70465285, 0.5457342, 0.33862746, 0.5457342, 0.33862746, -0.16137254, 0.33862746, 0.5457342, 0.33862746, 0.5457342, 0.70465285,
        0.5457342, 0.70465285, 0.5457342, 0.33862746, 0.5457342, 0.70465285, 0.5457342, 0.70465285,
    ];
    let to_world = [
        -2.1607270002238695e50, -8.794166855489053e50, 1.1475733941442131e51, -2.6042004286460423e49, 3.955601091442521e50, 1.0800880395553268e51, 9.021794945174574e50, -1.1889138216085182e51, -1.390622379304777e51, 4.438715280936198e50,
        7.831524876428574e49, 4.342178012234358e50,
    ];
    let grid = mf_grid { values: values.as_ptr(), nx: 3, ny: 3, nz: 3, to_world };
    let mut surface = ptr::null_mut();
    assert_eq!(unsafe { mf_surface_new_grid(&grid, &mut surface) }, mf_status::MF_OK, "{}", last_error());
    let level = 3.0000000000000002e50;
    for (v, f) in enclosure_vertices(surface, level, 8.468034533926575e49) {
        assert!(f >= level, "enclosure vertex {v:?} inside the region: f = {f:e} < level {level:e}");
    }
    unsafe { mf_surface_free(surface) };
}

/// `fuzz/artifacts/fields/crash-20276abe48ca25aaac6bbcda0ad3559e1626f4d4`: a gpss medium with
/// α = 1e-6 and `vndf_sampling = mixture` (seeds/000 Eq. 40), a field giving an anisotropy
/// matrix at a collision. The localized phase function evaluated the local distribution but kept
/// the medium's mixture sampler, whose α = 1e-6 flakes are invisible from `wi`:
/// `mf_phase_eval_pdf_local` answered a positive value with pdf 0 (that direction could never be
/// sampled: a biased render). The mixture is now rebuilt from the local gpss distribution, or
/// replaced by exact sampling for an anisotropy matrix (no Beckmann limit to mix with).
#[test]
fn localized_mixture_samples_the_local_distribution() {
    let m = medium(&[("sigma", 1e50), ("alpha", 1e-6), ("mixture_ratio", 9.99999999998998e-1)], &[("distribution", "gpss"), ("material", "Cr"), ("vndf_sampling", "mixture")]);
    let a = 1.124682650380666e97;
    let scale = 0.5003939084657291;
    let matrix = mf_local_params { set: 15, sigma: 2.3713737056616214e49, alpha: mf_vec3 { x: 10.0, y: 10.0, z: 10.0 }, anisotropy: [a, a, a, 0.0, 0.0, 0.0], reflectance_scale: mf_rgb { r: scale, g: scale, b: scale } };
    // The same point with a gpss roughness instead of a matrix: the mixture of the local gpss.
    let roughness = mf_local_params { set: 15 & !MF_LOCAL_ANISOTROPY, ..matrix };
    let frame = mf_frame {
        normal: mf_vec3 { x: 0.7387941811789444, y: 1.2222744014504094e-5, z: -0.6739311223758239 },
        tangent: mf_vec3 { x: 5.39454224564444e-6, y: -0.9999999999107517, z: -1.2222744014504094e-5 },
    };
    let wi = mf_vec3 { x: -0.9645746758295346, y: -0.02367927741330882, z: -0.26274509808849267 };
    let u = [0.27837550639712605, 0.18304711162126086, 0.7451439733298825, 0.0005698311946117363, 0.8281247457489371];
    for (name, local) in [("anisotropy", matrix), ("roughness", roughness)] {
        let mut v = mf_phase_value { value: mf_rgb { r: -1.0, g: -1.0, b: -1.0 }, pdf: -1.0 };
        assert_eq!(unsafe { mf_phase_eval_pdf_local(m, &local, &frame, wi, mf_vec3 { x: 0.0, y: 1.0, z: 0.0 }, &mut v) }, mf_status::MF_OK, "{}", last_error());
        assert!(v.value.r > 0.0 && v.pdf > 0.0, "{name}: eval {:?} with pdf {}", v.value, v.pdf);
        let mut s = std::mem::MaybeUninit::<mf_phase_sample_result>::uninit();
        assert_eq!(unsafe { mf_phase_sample_local(m, &local, &frame, wi, u.as_ptr(), s.as_mut_ptr()) }, mf_status::MF_OK, "{}", last_error());
        let s = unsafe { s.assume_init() };
        assert!(s.valid && s.pdf > 0.0, "{name}: {s:?}");
    }
    unsafe { mf_medium_free(m) };
}

/// `fuzz/artifacts/tracking/crash-2d7190b1a36507c62cae84f278d873e98e51484c`: a sphere of radius
/// 5.8e-36 centred at (0, 1, 2), its enclosure at level 5.2e-35 with cells of 2e-36, far below
/// an ulp of the coordinates (2.2e-16): the vertices `lo + g h` rounded onto (x, 1, 2), inside
/// the region (f = 4.97e-35 < level). Cells are now at least 1e5 ulps of the largest
/// coordinate, so the region lies inside a few of them.
#[test]
fn enclosure_far_from_the_origin_contains_the_region() {
    let mut sphere = ptr::null_mut();
    let pole = mf_vec3 { x: 0.0, y: -1.0, z: 0.0 };
    assert_eq!(unsafe { mf_surface_new_sphere(mf_vec3 { x: 0.0, y: 1.0, z: 2.0 }, 5.782903863735844e-36, false, pole, &mut sphere) }, mf_status::MF_OK);
    let level = 5.166912686415101e-35;
    for (v, f) in enclosure_vertices(sphere, level, 1.9996642309308483e-36) {
        assert!(f >= level, "enclosure vertex {v:?} inside the region: f = {f:e} < level {level:e}");
    }
    unsafe { mf_surface_free(sphere) };
}

/// `fuzz/artifacts/tracking/crash-092b236ee5dc608bc5e4cee661535aa36e9f3217`: Beckmann at
/// α = 1e6 (σ = 1e-50), a tetrahedron 3e-46 wide, a ray from its top vertex region up along the
/// normal. The frame normals near an edge, `(q − c)/|q − c|` at 2.5e-56 from it, are rounded by
/// ~1e-5 rad (coordinates 3e-46 over the distance), beyond the segment bound's `d·n` range
/// (padded by 1e-12): `d·n` = 1 − 3e-16 against a range ending at 1 − 5.8e-12, where this lobe's
/// back-facing area is 0 while the exact lower bound (`Ndf::projected_area_bound`) was 0.54:
/// the control exceeded `σ_t` in 896 of 2001 transmittance calls. The mesh's range now widens by
/// that rounding at the piece's smallest distance (`src/surface/mesh/mod.rs`).
#[test]
fn mesh_normal_rounding_stays_inside_the_bound() {
    let m = medium(&[("sigma", 1e-50), ("lengthscale", 1.4142135623730953e-56)], &[("distribution", "beckmann")]);
    let (positions, indices) = tetrahedron(2.999998978784814e-46);
    let surface = accepted_mesh(&positions, &indices, None);
    let origin = mf_vec3 { x: 0.0, y: 0.0, z: 2.999998978781814e-46 };
    let d = mf_vec3 { x: -1.9883817500012286e-6, y: 1.0334886555964507e-6, z: 0.9999999999974891 };
    let counts = violations(m, surface, origin, d, 1.2118579560936542e-45, (0..2000).chain([42887017611264]));
    assert_eq!(counts, (0, 0), "majorant violations in free flights and transmittance");
}

/// `fuzz/artifacts/fields/crash-9c10c3022f257d6fd3afebd0e1754e8cab12d672`: a field's anisotropy
/// `Σ = diag(46.8, 1e-6, 1e-6)` at σ = 5.1e34 makes the roughness matrix `2σ²Σ⁻¹` reach
/// α ≈ 7e37, and `mf_phase_eval_pdf_local` answered `eval = +inf` with MF_OK (`det(Q)^{3/2}`
/// overflowed in D). A matrix whose roughness along the frame's axes exceeds 1e6 (the range of
/// `alpha_u`, `alpha_v`, `alpha_z`) is now refused with the reason.
#[test]
fn anisotropy_beyond_the_roughness_range_is_refused() {
    let m = medium(&[("sigma", 1e50), ("shell_extent", 1e-3), ("lengthscale", 1.4142135623730953e56)], &[("distribution", "gpss")]);
    let local = mf_local_params {
        set: 15,
        sigma: 5.080228710492773e34,
        alpha: mf_vec3 { x: 42.02709887639687, y: 999.9999999971164, z: 0.0 },
        anisotropy: [46.83690999171263, 1e-6, 1e-6, 0.0, 0.0, 0.0],
        reflectance_scale: mf_rgb { r: 0.6392156862745098, g: 0.6392156862745098, b: 0.6392156862745098 },
    };
    let frame = mf_frame { normal: mf_vec3 { x: -0.6158572565749079, y: -0.737018188584581, z: -0.2784313725490195 }, tangent: mf_vec3 { x: 1.0, y: 0.0, z: 0.0 } };
    let wi = frame.normal;
    let mut v = mf_phase_value { value: mf_rgb { r: -7.0, g: -7.0, b: -7.0 }, pdf: -7.0 };
    let status = unsafe { mf_phase_eval_pdf_local(m, &local, &frame, wi, wi, &mut v) };
    assert_eq!(status, mf_status::MF_ERROR_INVALID_ARGUMENT, "{v:?}");
    assert!(last_error().contains("roughness"), "{}", last_error());
    assert_eq!(v.pdf, -7.0, "written on failure");
    unsafe { mf_medium_free(m) };
}

/// A host surface that answers `f = −∞` (a unit normal) everywhere: its callbacks lie.
unsafe extern "C" fn minus_infinity_point(_: *mut std::ffi::c_void, _: mf_vec3, out: *mut mf_surface_point) -> i32 {
    let z = mf_vec3 { x: 0.0, y: 0.0, z: 1.0 };
    unsafe { *out = mf_surface_point { f: f64::NEG_INFINITY, normal: z, tangent: mf_vec3 { x: 1.0, y: 0.0, z: 0.0 }, u: 0.0, v: 0.0 } };
    0
}

/// `fuzz/artifacts/tracking/crash-b526ef07ad869586ea613edd9a7e0563d69a776f`: a callback surface
/// in a box of 1e-3 whose `f` turns −∞, `mf_surface_enclosure` at level −1e308 with cells of
/// 1e308: the grid's extent overflowed (the cell then became +∞), every block centre was NaN,
/// and the enclosure's vertices were NaN, with MF_OK. A grid beyond the range of f64 is now
/// refused with the reason, nothing written.
#[test]
fn enclosure_grid_beyond_f64_is_refused() {
    let surface = callback_surface(minus_infinity_point, MF_SURFACE_GENERAL, mf_vec3 { x: -1e-3, y: -1e-3, z: -1e-3 }, mf_vec3 { x: 1e-3, y: 1e-3, z: 1e-3 });
    for (level, cell) in [(-9.99947860136237e307, 9.999478601362363e307), (1e308, 0.0), (0.0, 1.7e308)] {
        let mut enclosure = ptr::null_mut();
        let status = unsafe { mf_surface_enclosure(surface, ptr::null_mut(), level, cell, &mut enclosure) };
        if status == mf_status::MF_OK {
            let mut mesh = std::mem::MaybeUninit::<mf_mesh>::uninit();
            assert_eq!(unsafe { mf_enclosure_mesh(enclosure, mesh.as_mut_ptr()) }, mf_status::MF_OK);
            let mesh = unsafe { mesh.assume_init() };
            let positions = unsafe { std::slice::from_raw_parts(mesh.positions, 3 * mesh.vertex_count) };
            assert!(positions.iter().all(|x| x.is_finite()), "level {level:e}, cell {cell:e}: a vertex is not finite");
            unsafe { mf_enclosure_free(enclosure) };
        } else {
            assert_eq!(status, mf_status::MF_ERROR_INVALID_ARGUMENT, "level {level:e}, cell {cell:e}");
            assert!(enclosure.is_null());
        }
    }
    unsafe { mf_surface_free(surface) };
}

/// A host sphere of radius 0 at the origin, `f = |p|` computed plainly (its squares underflow for
/// coordinates below ~1e-154, as a host's would).
unsafe extern "C" fn point_sphere(_: *mut std::ffi::c_void, p: mf_vec3, out: *mut mf_surface_point) -> i32 {
    let r = length(p);
    let n = if r > 0.0 { mf_vec3 { x: p.x / r, y: p.y / r, z: p.z / r } } else { mf_vec3 { x: 0.0, y: 0.0, z: 1.0 } };
    unsafe { *out = mf_surface_point { f: r, normal: n, tangent: mf_vec3 { x: 0.0, y: 0.0, z: 0.0 }, u: 0.0, v: 0.0 } };
    0
}

/// `fuzz/artifacts/tracking/crash-014cb22e01fc938cbd88de5efdc01fc41192bec3`: a point-like host
/// sphere (radius 0), `mf_surface_enclosure` at level 2.2e-308 with cells of 7e-310: the corners
/// lay where the host's squared distances underflow, so the host saw its own enclosure's
/// vertices at f = 0, inside the region. Cells are now at least 1e-53 (1e-3 of the smallest
/// sigma), where a host's f is exact to rounding.
#[test]
fn enclosure_cells_stay_above_underflow() {
    let zero = mf_vec3 { x: 0.0, y: 0.0, z: 0.0 };
    let surface = callback_surface(point_sphere, MF_SURFACE_CONVEX, zero, zero);
    let level = 2.2250738585072014e-308;
    // f as the host sees it.
    for (v, f) in enclosure_vertices(surface, level, 7.0363022809101e-310) {
        assert!(f >= level, "enclosure vertex {v:?} inside the region for the host: f = {f:e} < level {level:e}");
    }
    unsafe { mf_surface_free(surface) };
}

/// `fuzz/artifacts/tracking/crash-18c6f34f79c2316e57d65fcaa13a1b7ce0fff118`: a convex host
/// plane declaring a box from x = −1e308 to −2.4, `mf_surface_enclosure` at level 3e-50 with
/// cells of 1.44e307. The grid's far corner (1.2e308) is a number, but its offset from the near
/// one, 16 cells of 1.44e307, is not: a vertex at x = +inf came back with MF_OK. Such a grid is
/// now refused, naming the cells.
#[test]
fn enclosure_grid_offsets_stay_finite() {
    let bounds_min = mf_vec3 { x: -9.999996633235829e307, y: -416.4931306453479, z: -416.49313092669183 };
    let bounds_max = mf_vec3 { x: -2.3866660595298272, y: -9.776983104865359e-292, z: -1e-320 };
    let surface = callback_surface(tilted_plane, MF_SURFACE_CONVEX, bounds_min, bounds_max);
    let mut enclosure = ptr::null_mut();
    let status = unsafe { mf_surface_enclosure(surface, ptr::null_mut(), 3e-50, 1.441296652194311e307, &mut enclosure) };
    assert_eq!(status, mf_status::MF_ERROR_INVALID_ARGUMENT);
    assert!(enclosure.is_null());
    assert!(last_error().contains("exceeds the range of f64"), "{}", last_error());
    unsafe { mf_surface_free(surface) };
}

/// `fuzz/artifacts/fields/crash-0de418821a7eefcf9246d66d2d07661e4aaee241`: gpss α = 1e-6,
/// σ = 1e50, a flipped sphere of radius 3e49 around (−1e300, −1e300, −1e300), tracked from its
/// centre. 1.4e284 along the ray the points' coordinates are rounded by 1.5e284: a tentative
/// collision's normal was 60° off the segment's range of d·n, and σ_t broke the majorant; f there
/// was −inf (|p − c|² overflowed). The sphere's d·n range now widens by that rounding at the
/// segment's closest approach to the centre, and its distances do not overflow.
#[test]
fn sphere_normals_rounded_near_the_centre() {
    let m = medium(&[("sigma", 1e50), ("alpha", 1e-6)], &[("distribution", "gpss")]);
    let centre = mf_vec3 { x: -1e300, y: -1e300, z: -1e300 };
    let mut sphere = ptr::null_mut();
    assert_eq!(unsafe { mf_surface_new_sphere(centre, 3.0000008156029367e49, true, centre, &mut sphere) }, mf_status::MF_OK);
    let (status, point) = eval(sphere, mf_vec3 { x: -1e300, y: -9.999999999999999e299, z: -1e300 });
    assert_eq!(status, mf_status::MF_OK);
    assert!(point.f.is_finite() && point.f < -1e284, "{point:?}");
    let d = mf_vec3 { x: -0.3617261560819874, y: 0.8546118510735646, z: 0.37254901960784315 };
    let counts = violations_of_calls(m, sphere, centre, d, f64::INFINITY, (0..20).chain([5787213827046133840]), true);
    assert_eq!(counts, (0, 0), "majorant violations in free flights and transmittance");
    unsafe {
        mf_surface_free(sphere);
        mf_medium_free(m);
    }
}

/// `fuzz/corpus/tracking/b7f8d8b1…` (1.2 s per run): σ = 1e-50, Beckmann α = 1e-6, a ray deep
/// inside an octahedron of size 1000 (f ≈ −497), moving outward, where the majorant is 0. Each
/// empty segment asks for twice its length, but the tracker halved it back for looseness that
/// was the mesh's padding for rounding (2e-9, the same at any length): it crept on by 1e-50 and
/// failed after 65,536 segments. A halving that does not tighten the bound is now undone.
#[test]
fn empty_segments_deep_inside_a_mesh_grow() {
    let m = medium(&[("sigma", 1e-50), ("shell_extent", 9.99999999999e-4), ("alpha", 1e-6)], &[("distribution", "beckmann")]);
    let (positions, indices) = octahedron(1000.0000000010001);
    let (normals, _) = octahedron(1.0);
    let surface = accepted_mesh(&positions, &indices, Some(&normals));
    let q = mf_track_query { origin: mf_vec3 { x: -0.0002730159346467071, y: 0.00025508563872220756, z: 138.41286895550982 }, d: mf_vec3 { x: 0.0, y: 1.0, z: 0.0 }, t_max: 78.1264188243673, seed: 16276397599167177057, exit_level: 0.0, survival: 0.0, hint: 0 };
    let mut c = std::mem::MaybeUninit::<mf_collision>::uninit();
    let status = unsafe { mf_track_free_flight(m, surface, ptr::null(), ptr::null_mut(), &q, c.as_mut_ptr()) };
    assert_eq!(status, mf_status::MF_OK, "{}", last_error());
    let c = unsafe { c.assume_init() };
    // 510 segments since the fix (the doublings from 1e-50 to 78, with their halvings undone).
    assert!(c.stats.segments < 2000, "{:?}", c.stats);
    let mut t = mf_transmittance { transmittance: -1.0, t: 0.0, stats: mf_track_stats::default() };
    assert_eq!(unsafe { mf_track_transmittance(m, surface, ptr::null(), ptr::null_mut(), &q, &mut t) }, mf_status::MF_OK, "{}", last_error());
    assert!(t.stats.segments < 2000 && (0.0..=1.0).contains(&t.transmittance), "{t:?}");
    unsafe {
        mf_surface_free(surface);
        mf_medium_free(m);
    }
}

/// `fuzz/corpus/tracking/4863559a…`: σ = 1e50, gpss α = 1e-6 around a flipped unit sphere, a ray
/// from z = −4.9e64 along +z. At t = 2.8e64 the segment was shortened to 5.7e36, below the
/// rounding of t (5.8e48): the ray could not move, and every one of the 65,536 segments was the
/// same. Such a call now stops at the first one, saying why.
#[test]
fn segment_below_the_rounding_of_t_stops_the_call() {
    let m = medium(&[("sigma", 1e50), ("lengthscale", 1.4142135623730953e56)], &[("distribution", "gpss")]);
    let c = 1.000000000000001;
    let mut sphere = ptr::null_mut();
    assert_eq!(unsafe { mf_surface_new_sphere(mf_vec3 { x: c, y: c, z: c }, c, true, mf_vec3 { x: c, y: c, z: c }, &mut sphere) }, mf_status::MF_OK);
    let q = mf_track_query { origin: mf_vec3 { x: c, y: -1.4810521216686835e-267, z: -4.8587479139867144e64 }, d: mf_vec3 { x: 0.0003564864423334052, y: 0.0, z: 0.9999999364587062 }, t_max: f64::INFINITY, seed: 0, exit_level: 0.0, survival: 0.0, hint: 0 };
    let mut flight = std::mem::MaybeUninit::<mf_collision>::uninit();
    let status = unsafe { mf_track_free_flight(m, sphere, ptr::null(), ptr::null_mut(), &q, flight.as_mut_ptr()) };
    assert_eq!(status, mf_status::MF_ERROR_INVALID_ARGUMENT);
    // (Where it stalls depends on the segments' reach: 4.2e64 since segments reach 6σ.)
    assert!(last_error().contains("stalled at t = ") && last_error().contains("below the rounding of t"), "{}", last_error());
    unsafe {
        mf_surface_free(sphere);
        mf_medium_free(m);
    }
}

/// `fuzz/artifacts/tracking/crash-d87974c0…`: an octahedron scaled by −3 (mirrored, so its
/// triangles wind clockwise seen from outside) was accepted. Its f < 0 filled the space around
/// it up to the bounding box, where f turns positive, and `mf_surface_enclosure` put vertices
/// inside that region. An inside-out mesh is refused with the reason; the same mesh scaled by +3
/// is accepted.
#[test]
fn inside_out_mesh_is_refused() {
    for scale in [3.0, -3.0] {
        let (positions, indices) = octahedron(scale);
        let (status, surface) = new_mesh(&positions, &indices, None, None);
        if scale > 0.0 {
            assert_eq!(status, mf_status::MF_OK, "{}", last_error());
            unsafe { mf_surface_free(surface) };
        } else {
            assert_eq!(status, mf_status::MF_ERROR_INVALID_ARGUMENT);
            assert!(last_error().contains("inside out") && last_error().contains("signed volume -3.6e1"), "{}", last_error());
            assert!(surface.is_null());
        }
    }
}

/// `fuzz/artifacts/fields/crash-e118af36…`: one triangle given twice with the same winding
/// (every edge used twice, so it passed as closed) made a closest-point query find no triangle:
/// a panic (index 4294967295). Meshes whose edges are not crossed as often in one direction as
/// in the other are refused with the reason, and so is an octahedron with one triangle flipped.
#[test]
fn inconsistent_winding_is_refused() {
    let s = 1096.9295554501955;
    let triangle = [s, 0.0, 0.0, 0.0, s, 0.0, 0.0, 0.0, s];
    let (octahedron, mut flipped_one) = octahedron(1.0);
    flipped_one.swap(1, 2);
    let cases: [(&[f64], &[u32]); 3] = [(&triangle, &[0, 1, 2, 0, 1, 2]), (&triangle, &[0, 2, 1, 0, 2, 1]), (&octahedron, &flipped_one)];
    for (positions, indices) in cases {
        assert_eq!(new_mesh(positions, indices, None, None).0, mf_status::MF_ERROR_INVALID_ARGUMENT, "{indices:?}");
        assert!(last_error().contains("winding is inconsistent"), "{indices:?}: {}", last_error());
    }
}

/// `fuzz/artifacts/tracking/crash-fac063b4…`: a sphere's pole of length ~1.8e-162 was normalised
/// through its squared length, which is subnormal: `mf_surface_eval` at the centre (where the
/// normal is the pole) answered a normal of length 1.0000118 (0.798 for the pole below).
#[test]
fn tiny_sphere_pole_is_a_unit_normal() {
    let zero = mf_vec3 { x: 0.0, y: 0.0, z: 0.0 };
    for pole in [mf_vec3 { x: 1.7721047679881543e-162, y: 0.0, z: 0.0 }, mf_vec3 { x: 1.7721047679881543e-162, y: -2.975777e-298, z: 1e-163 }] {
        let mut sphere = ptr::null_mut();
        assert_eq!(unsafe { mf_surface_new_sphere(zero, 2.858251005505063e-17, true, pole, &mut sphere) }, mf_status::MF_OK);
        let (status, point) = eval(sphere, zero);
        assert_eq!(status, mf_status::MF_OK);
        let n = point.normal;
        let length = length(n);
        assert!((length - 1.0).abs() < 1e-12, "{pole:?}: normal {n:?}, length {length}");
        unsafe { mf_surface_free(sphere) };
    }
}

/// `fuzz/artifacts/tracking/crash-dd7b51a5…`: an octahedron 4 wide (vertex normals), a ray from
/// (−1e308, 0, −1.8e308). Scaled by 2^-1023 for the far closest-point test, the mesh's edges were
/// subnormal and every distance NaN: no triangle was found, a panic (MF_ERROR_INTERNAL through
/// the ABI). From there the mesh is one point: its first vertex.
#[test]
fn mesh_seen_from_the_end_of_f64() {
    let m = medium(&[("sigma", 1e50), ("alpha", 1e-6)], &[("distribution", "beckmann")]);
    let (positions, indices) = octahedron(2.0);
    let (unit, _) = octahedron(1.0);
    let surface = accepted_mesh(&positions, &indices, Some(&unit));
    let origin = mf_vec3 { x: -9.999999999997382e307, y: -8.524953868804761e-198, z: -1.7976931348623157e308 };
    let (status, point) = eval(surface, origin);
    assert_eq!(status, mf_status::MF_OK, "{}", last_error());
    let n = point.normal;
    assert!(point.f > 0.0 && (length(n) - 1.0).abs() < 1e-12, "{point:?}");
    let q = mf_track_query { origin, d: mf_vec3 { x: 6.9510363278929e-7, y: 0.0, z: 0.9999999999997584 }, t_max: f64::INFINITY, seed: 0, exit_level: 0.0, survival: 0.0, hint: 0 };
    let mut c = std::mem::MaybeUninit::<mf_collision>::uninit();
    let status = unsafe { mf_track_free_flight(m, surface, ptr::null(), ptr::null_mut(), &q, c.as_mut_ptr()) };
    assert!(status == mf_status::MF_OK || status == mf_status::MF_ERROR_INVALID_ARGUMENT, "{status:?}: {}", last_error());
    unsafe {
        mf_surface_free(surface);
        mf_medium_free(m);
    }
}

const FAR_PLANE_NORMAL: [f64; 3] = [-0.5911580073262839, 0.6404998771853718, -0.49019599926921154];
const FAR_PLANE_OFFSET: f64 = -9.651692089942455e49;

unsafe extern "C" fn far_plane(_: *mut std::ffi::c_void, p: mf_vec3, out: *mut mf_surface_point) -> i32 {
    let [x, y, z] = FAR_PLANE_NORMAL;
    unsafe { *out = mf_surface_point { f: x * p.x + y * p.y + z * p.z - FAR_PLANE_OFFSET, normal: mf_vec3 { x, y, z }, tangent: mf_vec3 { x: 1.0, y: 0.0, z: 0.0 }, u: 0.0, v: 0.0 } };
    0
}

/// `fuzz/artifacts/fields/crash-5a5f8da7…`: σ = 1e50, an honest plane, a ray from z = −1e225
/// crossing it at t ≈ 1e225. The tentative collisions `origin + t d` near z = −4e221 were off by
/// an ulp of t (1.5e209), while the bounds of `f` were widened by the rounding of the points'
/// own coordinates (4e206): σ_t exceeded the majorant by 1e158 in every call. The widening now
/// counts `t`; 1e159 σ of rounding leaves the majorant too loose to finish, and the calls end
/// with the tentative cap's error, naming the cause, never MF_OK with a broken majorant.
#[test]
fn plane_majorant_holds_far_along_the_ray() {
    let m = medium(&[("sigma", 1e50), ("alpha", 3.0)], &[("distribution", "gpss")]);
    let everything = (mf_vec3 { x: f64::NEG_INFINITY, y: f64::NEG_INFINITY, z: f64::NEG_INFINITY }, mf_vec3 { x: f64::INFINITY, y: f64::INFINITY, z: f64::INFINITY });
    let surface = callback_surface(far_plane, MF_SURFACE_CONCAVE, everything.0, everything.1);
    let origin = mf_vec3 { x: -1.3621627434734314e50, y: -3.816233434913849e50, z: -1.0198671032402877e225 };
    let d = glam::DVec3::new(-0.00022257322900991308, -0.0004917331059362258, 0.9999988543297802).normalize();
    for seed in 0..4 {
        let q = mf_track_query { origin, d: mf_vec3 { x: d.x, y: d.y, z: d.z }, t_max: f64::INFINITY, seed, exit_level: 0.0, survival: 0.0, hint: 0 };
        let mut c = std::mem::MaybeUninit::<mf_collision>::uninit();
        match unsafe { mf_track_free_flight(m, surface, ptr::null(), ptr::null_mut(), &q, c.as_mut_ptr()) } {
            mf_status::MF_OK => assert_eq!(unsafe { c.assume_init() }.stats.majorant_violations, 0, "seed {seed}"),
            _ => assert!(last_error().contains("rounding of the coordinates"), "seed {seed}: {}", last_error()),
        }
        let mut t = mf_transmittance { transmittance: -1.0, t: 0.0, stats: mf_track_stats::default() };
        match unsafe { mf_track_transmittance(m, surface, ptr::null(), ptr::null_mut(), &q, &mut t) } {
            mf_status::MF_OK => assert_eq!(t.stats.majorant_violations, 0, "seed {seed}"),
            _ => assert!(last_error().contains("rounding of the coordinates"), "seed {seed}: {}", last_error()),
        }
    }
    unsafe {
        mf_surface_free(surface);
        mf_medium_free(m);
    }
}

unsafe extern "C" fn no_params(_: *mut std::ffi::c_void, _: mf_vec3, _: *const mf_surface_point, out: *mut mf_local_params) -> i32 {
    unsafe { *out = std::mem::zeroed() };
    0
}

unsafe extern "C" fn no_bounds(_: *mut std::ffi::c_void, _: mf_vec3, _: mf_vec3, _: f64, out: *mut mf_param_bounds) -> i32 {
    unsafe { *out = std::mem::zeroed() };
    0
}

/// `fuzz/artifacts/fields/crash-e4c1fdd3…`: a field declaring `sigma_max = DBL_MAX` made the
/// region's heights σ = 1.8e308: the first segment was infinitely long, its Lipschitz lower bound
/// of f went to −∞, the line through it lost its slope, and σ_t exceeded the majorant at the
/// first tentative collision. `sigma_max` beyond the domain of sigma is refused with the reason.
#[test]
fn field_sigma_max_beyond_the_domain_is_refused() {
    for (sigma_max, ok) in [(f64::MAX, false), (1e51, false), (1e-51, false), (1e50, true), (0.0, true)] {
        let callbacks = mf_field_callbacks { at: Some(no_params), bounds: Some(no_bounds), sigma_max };
        let mut field = ptr::null_mut();
        let status = unsafe { mf_field_new_callbacks(&callbacks, &mut field) };
        if ok {
            assert_eq!(status, mf_status::MF_OK, "{sigma_max:e}: {}", last_error());
            unsafe { mf_field_free(field) };
        } else {
            assert_ne!(status, mf_status::MF_OK, "{sigma_max:e}");
            assert!(last_error().contains("callbacks->sigma_max") && field.is_null(), "{sigma_max:e}: {}", last_error());
        }
    }
}

/// `fuzz/artifacts/tracking/crash-a18df8e8…`: an octahedron 2.9e-50 wide with one vertex moved to
/// 1.1e-35: at a point within the mesh's rounding of an edge, the normal is the edge's
/// pseudo-normal, the sum of two nearly opposite face normals (length 1.4e-160) normalised
/// through its subnormal squared length: 1.0000167 long. It is rescaled first now.
#[test]
fn mesh_normal_near_an_edge_is_unit() {
    let s = 1.4504026155174787e-50;
    let (mut positions, indices) = octahedron(s);
    positions[..3].copy_from_slice(&[-7.796264947706224e-196, -1.1116935433363922e-35, -2.8247524380560736e-185]);
    let surface = accepted_mesh(&positions, &indices, None);
    let p = mf_vec3 { x: -6.611290867050549e-50, y: -6.597909937255984e-50, z: -1.1597177579103332e-49 };
    let (status, point) = eval(surface, p);
    assert_eq!(status, mf_status::MF_OK, "{}", last_error());
    let n = point.normal;
    let length = length(n);
    assert!((length - 1.0).abs() < 1e-12, "normal {n:?}, length {length}");
    unsafe { mf_surface_free(surface) };
}

/// `fuzz/artifacts/fields/crash-bb6a0e1f…`: an octahedron with two pairs of vertices merged and
/// one moved to (40, −2, 0): sliver triangles 5e-37 wide and 40 long, whose area rounds to zero
/// in the closest-point test (not in their normals). Every distance in a cell's list was NaN, no
/// triangle was found: a panic (MF_ERROR_INTERNAL through the ABI). Slivers are their edges now.
#[test]
fn sliver_triangles_have_a_closest_point() {
    let s = 5.399562187234506e-37;
    let positions = [-s, 0.0, 0.0, -s, 0.0, 0.0, 0.0, -s, 0.0, 0.0, -s, 0.0, 40.0, -2.0762999195102028, 1.2760930781151428e-261, 0.0, 0.0, -s];
    let (_, indices) = octahedron(s);
    let surface = accepted_mesh(&positions, &indices, None);
    // The point of the artifact, then points around the mesh at its two scales.
    let mut rng = macrofacet::rng::Pcg32::new(5, 0);
    for k in 0..20_000 {
        let scale = [1e-37, 1e-36, 1e-30, 1.0, 40.0][k % 5];
        let random = mf_vec3 { x: (2.0 * rng.next_f64() - 0.5) * scale, y: (2.0 * rng.next_f64() - 1.0) * scale, z: (2.0 * rng.next_f64() - 1.0) * scale };
        let p = if k == 0 { mf_vec3 { x: 6.0, y: 6.0, z: -3.6470587769508733 } } else { random };
        let (status, point) = eval(surface, p);
        assert_eq!(status, mf_status::MF_OK, "{p:?}: {}", last_error());
        let n = point.normal;
        assert!(!point.f.is_nan() && (length(n) - 1.0).abs() < 1e-9, "{p:?}: {point:?}");
    }
    unsafe { mf_surface_free(surface) };
}

/// `fuzz/artifacts/fields/crash-9c0e51d4…`: a tetrahedron with one vertex moved to ~3e12. The
/// segment bound dropped each candidate triangle whose lower line stayed above the chord of the
/// closest one, and rounding dropped that one too: no candidate was left, a panic
/// (MF_ERROR_INTERNAL through the ABI). The chord's own triangle always stays.
#[test]
fn segment_bound_keeps_a_candidate() {
    let m = medium(&[("sigma", 3.0), ("alpha", 1e-6)], &[("distribution", "ggx")]);
    let a = 0.9000000004163026;
    let (mut positions, indices) = tetrahedron(a);
    positions[..3].copy_from_slice(&[-2954598395594.5703, -2169866234929.383, -2955209234974.085]);
    let surface = accepted_mesh(&positions, &indices, None);
    let origin = mf_vec3 { x: -1.4947998053850968, y: 0.4235294119557993, z: 0.42352941196061145 };
    let d = mf_vec3 { x: -0.9826117664013281, y: -0.1836819729199024, z: 0.027113972215260865 };
    for seed in (0..200).chain([18446744073709520775]) {
        let q = mf_track_query { origin, d, t_max: 9.000000004163024, seed, exit_level: 0.0, survival: 0.0, hint: 0 };
        let mut c = std::mem::MaybeUninit::<mf_collision>::uninit();
        let status = unsafe { mf_track_free_flight(m, surface, ptr::null(), ptr::null_mut(), &q, c.as_mut_ptr()) };
        assert_ne!(status, mf_status::MF_ERROR_INTERNAL, "seed {seed}: {}", last_error());
        let mut t = mf_transmittance { transmittance: -1.0, t: 0.0, stats: mf_track_stats::default() };
        let status = unsafe { mf_track_transmittance(m, surface, ptr::null(), ptr::null_mut(), &q, &mut t) };
        assert_ne!(status, mf_status::MF_ERROR_INTERNAL, "seed {seed}: {}", last_error());
    }
    unsafe {
        mf_surface_free(surface);
        mf_medium_free(m);
    }
}

/// `fuzz/artifacts/tracking/crash-c2aefd283ac5b1c32e8108ed604368e2b6b94e09`: Beckmann α = 1e-6,
/// σ = 3.2e-5 with shell_extent 39.8, a tetrahedron of half-width 1.3e-4 with vertex normals, a
/// ray along +x from x = −7.48 through the middle of an edge. A segment began at `origin + t d`,
/// 2e-16 inside the edge, with the previous bound's end point, computed at `p + length d` 3e-17
/// outside it, as its start: the mesh took the segment as outside (its lower lines of |f| stay
/// positive from there), and its f_lo was |f| where f < 0. σ_t exceeded the majorant 3-fold, in
/// 690 of 2001 calls. Segments now start exactly where the last bound ended.
#[test]
fn tetrahedron_with_vertex_normals_keeps_its_majorant() {
    let m = medium(&[("sigma", 3.2022486216900434e-5), ("shell_extent", 3.9810717055349734e1), ("alpha", 1e-6)], &[("distribution", "beckmann")]);
    let (positions, indices) = tetrahedron(0.00012982094035436694);
    let normals = tetrahedron(1.0 / 3f64.sqrt()).0;
    let surface = accepted_mesh(&positions, &indices, Some(&normals));
    let origin = mf_vec3 { x: -7.480334634255856, y: 0.0, z: 0.0 };
    let d = mf_vec3 { x: 1.0, y: 0.0, z: 0.0 };
    let counts = violations(m, surface, origin, d, f64::INFINITY, (0..2000).chain([8402028473159873280]));
    assert_eq!(counts, (0, 0), "majorant violations in free flights and transmittance");
    unsafe {
        mf_surface_free(surface);
        mf_medium_free(m);
    }
}

/// `fuzz/artifacts/tracking/crash-953ec1c3dd2b3eb6ed71990953a4f3d733664656`: gpss α = 2 with
/// diffuse flakes, σ = 1e50, a sphere of radius 1.8e308 (`DBL_MAX`) around (0, 2, 1.8e308), so
/// that it passes near the origin, and a ray from there along +x. `|q − c| − r` is rounded by
/// ~2e292 there: f came out 0 at a point 1e49 outside, and σ_t broke the majorant at the first
/// tentative collision. The sphere's bounds of f now widen by its own rounding (calls may end
/// with the tentative cap's error, never MF_OK with a broken majorant).
#[test]
fn sphere_larger_than_its_rounding_keeps_its_majorant() {
    let m = medium(&[("sigma", 1e50), ("alpha", 2.0)], &[("distribution", "gpss"), ("micro_bsdf", "diffuse")]);
    let mut sphere = ptr::null_mut();
    let pole = mf_vec3 { x: 0.06154907091204532, y: 0.9979114411396278, z: 0.019607843137255054 };
    assert_eq!(unsafe { mf_surface_new_sphere(mf_vec3 { x: 0.0, y: 2.0, z: f64::MAX }, f64::MAX, false, pole, &mut sphere) }, mf_status::MF_OK);
    let origin = mf_vec3 { x: 0.00010553324773590148, y: 0.00013327550688079068, z: 3.273088311945043e-5 };
    let d = mf_vec3 { x: 0.9984251218556673, y: 0.011966078117535967, z: -0.05480957053271407 };
    let counts = violations_of_calls(m, sphere, origin, d, f64::INFINITY, (0..10).chain([2522065454634721540]), true);
    assert_eq!(counts, (0, 0), "majorant violations in free flights and transmittance");
    unsafe {
        mf_surface_free(sphere);
        mf_medium_free(m);
    }
}

/// `fuzz/artifacts/fields/crash-dc8af182326d0269e641f8aae04205c4680198b5`: gpss α = 1e-6, σ =
/// 1e50, a flipped sphere of radius `f64::MAX` around the origin, a ray from (−1e300, −1e300,
/// −1e300) with `t_max = +inf`. The sphere's clearance (its Lipschitz step, `|v|²` overflowing)
/// took the ray to t = 1.8e308, and the segment across the shell ran past `f64::MAX`: a
/// tentative collision where `|q| > f64::MAX` had `f = −inf`, broke the majorant, and came back
/// as MF_OK at `t = +inf`, `p = (−inf, inf, inf)`. No ray point beyond f64's range is formed
/// now, and the interval ends at `t = f64::MAX`: a collision, if any, is finite and within the
/// majorant, or the call fails with a message.
#[test]
fn ray_beyond_the_range_of_f64_is_never_a_collision() {
    let m = medium(&[("sigma", 1e50), ("alpha", 1e-6)], &[("distribution", "gpss"), ("material", "Cr")]);
    let mut sphere = ptr::null_mut();
    let pole = mf_vec3 { x: -1e300, y: -1e300, z: -1e300 };
    assert_eq!(unsafe { mf_surface_new_sphere(mf_vec3 { x: 0.0, y: 0.0, z: 0.0 }, f64::MAX, true, pole, &mut sphere) }, mf_status::MF_OK);
    let origin = mf_vec3 { x: -1e300, y: -1e300, z: -1e300 };
    let d = mf_vec3 { x: -0.364599518083765, y: 0.8533899574065312, z: 0.37254901960784315 };
    for seed in 0..20 {
        let q = mf_track_query { origin, d, t_max: f64::INFINITY, seed, exit_level: 0.0, survival: 0.0, hint: 0 };
        let mut c = std::mem::MaybeUninit::<mf_collision>::uninit();
        let status = unsafe { mf_track_free_flight(m, sphere, ptr::null(), ptr::null_mut(), &q, c.as_mut_ptr()) };
        if status != mf_status::MF_OK {
            assert!(!last_error().is_empty());
            continue;
        }
        let c = unsafe { c.assume_init() };
        assert_eq!(c.stats.majorant_violations, 0, "{c:?}");
        assert!(!c.scattered || (c.t.is_finite() && c.p.x.is_finite() && c.p.y.is_finite() && c.p.z.is_finite()), "{c:?}");
    }
    assert_eq!(violations_of_calls(m, sphere, origin, d, f64::INFINITY, 0..20, true), (0, 0));
    unsafe {
        mf_surface_free(sphere);
        mf_medium_free(m);
    }
}

/// `fuzz/artifacts/tracking/crash-5cddce980e0f25528ea6851296e31a372884d0c3`: gpss α = 1e-6,
/// σ = 1e50, shell_extent 1e-3; a flipped sphere of radius `f64::MAX` around (−8.6e307,
/// −1.3e308, 3.7e307). A tentative collision on its shell, 1.65e308 along the ray, was
/// 1.797e308 from the centre: `|p − c|` rounded past `f64::MAX` to +inf, so f = −inf there
/// (the point lies on the shell), σ_t = inf broke the majorant, and the call answered MF_OK. The
/// sphere halves `p − c` where its length would overflow; f is then as representable as the
/// distance to the sphere.
#[test]
fn sphere_distance_near_f64_max_does_not_overflow() {
    let m = medium(&[("sigma", 1e50), ("shell_extent", 9.99999999999e-4), ("alpha", 1e-6)], &[("distribution", "gpss")]);
    let mut sphere = ptr::null_mut();
    let center = mf_vec3 { x: -8.564975663440448e307, y: -1.2576352121682895e308, z: 3.742620939433999e307 };
    let pole = mf_vec3 { x: 1.9383857733866474e-5, y: 6.900967161966396e-7, z: 0.9999999998118949 };
    assert_eq!(unsafe { mf_surface_new_sphere(center, f64::MAX, true, pole, &mut sphere) }, mf_status::MF_OK);
    // The tentative collision of the artifact: on the shell, to f64's rounding there (~1e292).
    let (status, point) = eval(sphere, mf_vec3 { x: -1.3858895369324425e308, y: 3.058422007288973e307, z: 1.0862895709187997e308 });
    assert_eq!(status, mf_status::MF_OK);
    assert!(point.f.is_finite() && point.f.abs() < 1e300, "{point:?}");
    let origin = mf_vec3 { x: -8.991263542916249e307, y: -1.1317516564109677e308, z: 4.315917196292113e307 };
    let d = mf_vec3 { x: -0.29448148859893886, y: 0.8697140501762715, z: 0.39607843137254917 };
    let counts = violations_of_calls(m, sphere, origin, d, f64::INFINITY, (0..10).chain([5570193308531903821]), true);
    assert_eq!(counts, (0, 0), "majorant violations in free flights and transmittance");
    unsafe {
        mf_surface_free(sphere);
        mf_medium_free(m);
    }
}

