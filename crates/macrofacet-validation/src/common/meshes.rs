//! Triangle meshes for the tests: closed, consistently oriented (counter-clockwise seen from
//! outside), with optional smooth vertex normals.
#![allow(dead_code)]

use glam::DVec3;
use std::f64::consts::PI;

pub struct Mesh {
    pub positions: Vec<DVec3>,
    pub indices: Vec<[u32; 3]>,
    pub normals: Option<Vec<DVec3>>,
}

/// A torus around the z axis: major radius `big`, tube radius `small`, `u` segments around the
/// axis and `v` around the tube, with analytic vertex normals.
pub fn torus(big: f64, small: f64, u: usize, v: usize) -> Mesh {
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    for i in 0..u {
        let phi = 2.0 * PI * i as f64 / u as f64;
        for j in 0..v {
            let theta = 2.0 * PI * j as f64 / v as f64;
            let n = DVec3::new(theta.cos() * phi.cos(), theta.cos() * phi.sin(), theta.sin());
            let c = DVec3::new(big * phi.cos(), big * phi.sin(), 0.0);
            positions.push(c + small * n);
            normals.push(n);
        }
    }
    let id = |i: usize, j: usize| ((i % u) * v + (j % v)) as u32;
    let mut indices = Vec::new();
    for i in 0..u {
        for j in 0..v {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            indices.push([a, b, c]);
            indices.push([a, c, d]);
        }
    }
    Mesh { positions, indices, normals: Some(normals) }
}

/// A UV sphere of radius `r` with `rings` x `segments` quads and analytic vertex normals.
pub fn uv_sphere(r: f64, rings: usize, segments: usize) -> Mesh {
    let mut positions = vec![DVec3::new(0.0, 0.0, r)];
    for i in 1..rings {
        let theta = PI * i as f64 / rings as f64;
        for j in 0..segments {
            let phi = 2.0 * PI * j as f64 / segments as f64;
            positions.push(r * DVec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()));
        }
    }
    positions.push(DVec3::new(0.0, 0.0, -r));
    let south = (positions.len() - 1) as u32;
    let ring = |i: usize, j: usize| (1 + (i - 1) * segments + j % segments) as u32;
    let mut indices = Vec::new();
    for j in 0..segments {
        indices.push([0, ring(1, j), ring(1, j + 1)]);
        indices.push([south, ring(rings - 1, j + 1), ring(rings - 1, j)]);
    }
    for i in 1..rings - 1 {
        for j in 0..segments {
            indices.push([ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)]);
            indices.push([ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)]);
        }
    }
    let normals = positions.iter().map(|p| p.normalize()).collect();
    Mesh { positions, indices, normals: Some(normals) }
}

/// A closed prism of height `h` (z from 0 to h) over a simple counter-clockwise polygon.
/// No vertex normals: sharp edges, the frame normal is the distance gradient.
pub fn prism(polygon: &[(f64, f64)], h: f64) -> Mesh {
    let n = polygon.len();
    let mut positions: Vec<DVec3> = polygon.iter().map(|&(x, y)| DVec3::new(x, y, 0.0)).collect();
    positions.extend(polygon.iter().map(|&(x, y)| DVec3::new(x, y, h)));
    let mut indices = Vec::new();
    // Caps by ear clipping (the polygons used here are simple).
    let mut ears: Vec<usize> = (0..n).collect();
    let area2 = |a: (f64, f64), b: (f64, f64), c: (f64, f64)| (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0);
    while ears.len() > 3 {
        let m = ears.len();
        let k = (0..m)
            .find(|&k| {
                let (a, b, c) = (polygon[ears[(k + m - 1) % m]], polygon[ears[k]], polygon[ears[(k + 1) % m]]);
                area2(a, b, c) > 0.0
                    && ears.iter().all(|&q| {
                        let p = polygon[q];
                        p == a || p == b || p == c || !(area2(a, b, p) >= 0.0 && area2(b, c, p) >= 0.0 && area2(c, a, p) >= 0.0)
                    })
            })
            .expect("simple polygon");
        let (a, b, c) = (ears[(k + m - 1) % m] as u32, ears[k] as u32, ears[(k + 1) % m] as u32);
        indices.push([a, c, b]); // bottom faces down
        indices.push([a + n as u32, b + n as u32, c + n as u32]);
        ears.remove(k);
    }
    let (a, b, c) = (ears[0] as u32, ears[1] as u32, ears[2] as u32);
    indices.push([a, c, b]);
    indices.push([a + n as u32, b + n as u32, c + n as u32]);
    for i in 0..n {
        let j = (i + 1) % n;
        let (a, b, c, d) = (i as u32, j as u32, (j + n) as u32, (i + n) as u32);
        indices.push([a, b, c]);
        indices.push([a, c, d]);
    }
    Mesh { positions, indices, normals: None }
}

/// The unit cube [-1, 1]^3 as 12 triangles, sharp edges.
pub fn cube() -> Mesh {
    let mut m = prism(&[(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)], 2.0);
    for p in &mut m.positions {
        p.z -= 1.0;
    }
    m
}

/// An L-shaped prism: a non-convex solid with a sharp reflex edge along z.
pub fn l_prism() -> Mesh {
    prism(&[(0.0, 0.0), (2.0, 0.0), (2.0, 1.0), (1.0, 1.0), (1.0, 2.0), (0.0, 2.0)], 1.0)
}

/// A lumpy, irregular closed surface: a torus whose vertices are moved along their normals by
/// up to `bumps` of the tube radius (deterministic pseudo-random), without vertex normals, so
/// that every edge has its own dihedral angle, convex and concave.
pub fn lumpy_torus(big: f64, small: f64, u: usize, v: usize, bumps: f64) -> Mesh {
    let mut m = torus(big, small, u, v);
    let normals = m.normals.take().expect("torus normals");
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    for (p, n) in m.positions.iter_mut().zip(&normals) {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        let jitter = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
        *p += 2.0 * bumps * small * jitter * *n;
    }
    m
}
