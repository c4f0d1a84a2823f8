//! Mean surfaces from fuzz bytes, built through the ABI (`mf_surface_new_sphere`, `_mesh`,
//! `_grid`, `_callbacks`) with every refusal checked: mostly valid ones of a size drawn around
//! the medium's shell, sometimes degenerate (zero-area or collinear triangles, open or
//! duplicated meshes, out-of-range indices, non-unit vertex normals, grids whose border is not
//! outside, transforms that are no similarity, non-finite values, NULL arrays).

use crate::check;
use crate::host::{BoundSource, Script, Shape, SurfaceHost};
use crate::input::{vec3, Bytes};
use glam::DVec3;
use macrofacet_ffi::*;
use std::ptr;

/// An `mf_surface`, freed on drop.
pub struct Surface(pub *mut mf_surface);

impl Drop for Surface {
    fn drop(&mut self) {
        // SAFETY: from an mf_surface_new_* function, freed once.
        unsafe { mf_surface_free(self.0) };
    }
}

/// A surface from [`surface`].
pub struct Built {
    pub surface: Surface,
    /// The host behind a callback surface.
    pub host: Option<SurfaceHost>,
    /// A built-in surface undamaged: a closed mesh or a grid of true distances, whose bounds
    /// must hold (damaged ones are no signed distance, and the tracker may count violations).
    pub exact: bool,
}

/// A surface of about `size` scene units around `center`; `None` when the ABI refused it (the
/// refusal itself is checked).
pub fn surface(b: &mut Bytes, size: f64, center: DVec3) -> Option<Built> {
    let debug = std::env::var_os("MF_FUZZ_DEBUG").is_some();
    match b.u8() % 4 {
        0 => {
            let center = if b.u8() % 8 == 0 { DVec3::new(b.float(), b.float(), b.float()) } else { center };
            let radius = if b.u8() % 8 == 0 { b.float() } else { size };
            let flip = b.u8() % 4 == 0;
            let pole = match b.u8() % 8 {
                0 => DVec3::new(b.float(), b.float(), b.float()),
                1 => DVec3::ZERO,
                _ => b.sphere(),
            };
            if debug {
                eprintln!("sphere: center {center} radius {radius:e} flip {flip} pole {pole}");
            }
            let s = check::call(|o| unsafe { mf_surface_new_sphere(vec3(center), radius, flip, vec3(pole), o) }).ok()?;
            Some(Built { surface: Surface(s), host: None, exact: true })
        }
        1 => mesh(b, size, center, debug).map(|(surface, exact)| Built { surface, host: None, exact }),
        2 => grid(b, size, center, debug).map(|(surface, exact)| Built { surface, host: None, exact }),
        _ => {
            let shape = if b.bool() {
                Shape::Sphere { center, radius: size }
            } else {
                Shape::Plane { normal: b.sphere(), offset: b.signed_distance(size) }
            };
            let bounds = b.choose(&[BoundSource::Lipschitz, BoundSource::Convex, BoundSource::Concave, BoundSource::Callback, BoundSource::Callback]);
            let host = SurfaceHost { shape, bounds, script: Script::draw(b) };
            let callbacks = host.callbacks(b);
            if debug {
                eprintln!("callback surface: {host:?} {callbacks:?}");
            }
            let s = check::call(|o| unsafe { mf_surface_new_callbacks(&callbacks, o) }).ok()?;
            Some(Built { surface: Surface(s), host: Some(host), exact: host.declares_its_box(&callbacks) })
        }
    }
}

/// A triangle mesh: a closed solid (tetrahedron, octahedron) scaled to `size`, or a degenerate
/// one (then not `exact`); vertex normals and uvs sometimes.
fn mesh(b: &mut Bytes, size: f64, center: DVec3, debug: bool) -> Option<(Surface, bool)> {
    let kind = b.u8() % 8;
    let mut exact = kind <= 4;
    const TETRAHEDRON: ([[f64; 3]; 4], [[u32; 3]; 4]) = ([[1.0, 1.0, 1.0], [1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0]], [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]]);
    const OCTAHEDRON: ([[f64; 3]; 6], [[u32; 3]; 8]) = (
        [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]],
        [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]],
    );
    let (mut positions, mut indices): (Vec<DVec3>, Vec<[u32; 3]>) = match kind {
        0 | 1 | 2 => (TETRAHEDRON.0.iter().map(|p| DVec3::from(*p)).collect(), TETRAHEDRON.1.to_vec()),
        3 | 4 => (OCTAHEDRON.0.iter().map(|p| DVec3::from(*p)).collect(), OCTAHEDRON.1.to_vec()),
        // One open triangle, or all vertices equal, or collinear ones.
        5 => (vec![DVec3::X, DVec3::Y, DVec3::Z], vec![[0, 1, 2]]),
        6 => (vec![DVec3::ZERO; 3], vec![[0, 1, 2], [0, 2, 1]]),
        _ => (vec![DVec3::ZERO, DVec3::X, 2.0 * DVec3::X, DVec3::Y], vec![[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]]),
    };
    for p in &mut positions {
        *p = center + size * *p;
    }
    // Damage: a moved vertex (sometimes non-finite), a duplicated or flipped triangle, a bad index.
    for _ in 0..b.below(3) {
        let damage = b.u8() % 6;
        exact &= damage == 4;
        match damage {
            0 => {
                let i = b.below(positions.len() - 1);
                positions[i] = if b.bool() { DVec3::new(b.float(), b.float(), b.float()) } else { positions[(i + 1) % positions.len()] };
            }
            1 => indices.push(indices[0]),
            2 => {
                let t = &mut indices[0];
                t.swap(0, 1);
            }
            3 => indices[0][2] = b.u32() % (positions.len() as u32 + 2),
            4 => {
                let i = b.below(positions.len() - 1);
                positions[i] += size * 1e-9 * b.sphere();
            }
            _ => indices.truncate(indices.len().saturating_sub(1).max(1)),
        }
    }
    let normals: Option<Vec<f64>> = match b.u8() % 4 {
        0 => Some(positions.iter().flat_map(|p| (*p - center).try_normalize().unwrap_or(DVec3::Z).to_array()).collect()),
        1 if b.u8() % 4 == 0 => Some(positions.iter().flat_map(|_| [b.float(), b.float(), b.float()]).collect()),
        _ => None,
    };
    let uvs: Option<Vec<f64>> = if b.u8() % 4 == 0 { Some(positions.iter().flat_map(|_| [b.unit(), b.float()]).collect()) } else { None };
    let flat_positions: Vec<f64> = positions.iter().flat_map(|p| p.to_array()).collect();
    let flat_indices: Vec<u32> = indices.iter().flatten().copied().collect();
    let null_arrays = b.u8() % 32 == 0;
    let mesh = mf_mesh {
        positions: if null_arrays && b.bool() { ptr::null() } else { flat_positions.as_ptr() },
        vertex_count: positions.len(),
        indices: if null_arrays && b.bool() { ptr::null() } else { flat_indices.as_ptr() },
        triangle_count: indices.len(),
        normals: normals.as_ref().map_or(ptr::null(), |n| n.as_ptr()),
        uvs: uvs.as_ref().map_or(ptr::null(), |u| u.as_ptr()),
    };
    // The reach: mostly none, else a thin shell's (about 1e-3 of the mesh's size) or any number
    // (NaN, zero and negative ones are refused).
    let reach = match b.u8() % 4 {
        0 => size * 1e-3 * (1.0 + b.unit()),
        1 if b.bool() => b.float(),
        _ => f64::INFINITY,
    };
    if debug {
        eprintln!("mesh: positions {positions:?} indices {indices:?} normals {normals:?} uvs {uvs:?} {mesh:?} reach {reach}");
    }
    // (One thread: the fuzzer's meshes are small, and the count does not change the surface.)
    check::call(|o| unsafe { mf_surface_new_mesh(&mesh, 1, reach, o) }).ok().map(|s| (Surface(s), exact))
}

/// A signed-distance grid of a sphere filling most of the unit cube, `n³` samples (n from 2),
/// scaled to `size` and rotated; sometimes with damaged values or transform.
fn grid(b: &mut Bytes, size: f64, center: DVec3, debug: bool) -> Option<(Surface, bool)> {
    let n = [2 + b.below(5), 2 + b.below(5), 2 + b.below(5)];
    let radius = 0.05 + 0.4 * b.unit();
    let scale = 2.0 * size;
    let mut values: Vec<f32> = Vec::with_capacity(n[0] * n[1] * n[2]);
    for z in 0..n[2] {
        for y in 0..n[1] {
            for x in 0..n[0] {
                let p = DVec3::new(x as f64, y as f64, z as f64) / DVec3::new((n[0] - 1) as f64, (n[1] - 1) as f64, (n[2] - 1) as f64);
                values.push(((p - DVec3::splat(0.5)).length() - radius) as f32);
            }
        }
    }
    let damaged = b.below(2);
    for _ in 0..damaged {
        let i = b.below(values.len() - 1);
        values[i] = b.choose(&[f32::NAN, f32::INFINITY, 0.0, -1.0, 1e30, f32::MIN_POSITIVE]);
    }
    // A rotation about a random axis times the scale, the cube centred on `center`.
    let axis = b.sphere();
    let rotation = glam::DMat3::from_axis_angle(axis, 2.0 * std::f64::consts::PI * b.unit());
    let mut linear = rotation * scale;
    match b.u8() % 16 {
        0 => linear.x_axis *= 2.0,
        1 => linear.x_axis = -linear.x_axis,
        2 => linear.y_axis.z = b.float(),
        _ => {}
    }
    let translation = center - linear * DVec3::splat(0.5);
    let c = [linear.x_axis, linear.y_axis, linear.z_axis];
    let to_world = [c[0].x, c[1].x, c[2].x, translation.x, c[0].y, c[1].y, c[2].y, translation.y, c[0].z, c[1].z, c[2].z, translation.z];
    let (nx, ny, nz) = match b.u8() % 32 {
        0 => (n[0], n[1], 1),
        1 => (0, n[1], n[2]),
        _ => (n[0], n[1], n[2]),
    };
    let grid = mf_grid { values: values.as_ptr(), nx, ny, nz, to_world };
    if debug {
        eprintln!("grid: {n:?} values {values:?} {grid:?}");
    }
    check::call(|o| unsafe { mf_surface_new_grid(&grid, o) }).ok().map(|s| (Surface(s), damaged == 0))
}
