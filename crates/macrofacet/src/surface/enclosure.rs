//! A closed triangle mesh that encloses the region `f < level` of a mean surface: what a host
//! puts into its ray tracer as the boundary of a macrofacet medium (the shell's top face is the
//! level `k σ`), so that no ray ever sphere-traces the level set.
//!
//! Built from cubes of a grid: a cell is kept when it may meet the region, which the Lipschitz
//! bound decides from one query at its centre (`f(x) >= f(c) − |x − c|`), and the enclosure is
//! the boundary between kept and dropped cells. It is therefore conservative by construction (no
//! point of the region lies outside it), watertight and free of self-intersections; it lies
//! within one cell diagonal of the level set. Blocks of cells are halved only where the same
//! bound at their centre leaves them undecided, so the queries follow the level set.

use super::MeanSurface;
use crate::error::{Error, ErrorKind, Result};
use glam::{DVec3, IVec3};
use std::collections::HashMap;

/// Fine cells per coarse block edge (a power of two: blocks halve down to cells).
const BLOCK: i32 = 8;
/// The largest grid, in fine cells along the longest axis (the cell grows beyond it).
const MAX_CELLS: f64 = 512.0;

/// A triangle mesh: positions and counter-clockwise (seen from outside) triangles.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Enclosure {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
    /// The cell size used.
    pub cell: f64,
}

/// The enclosure of `f < level` with cells of about `cell` (0: 1/128 of the surface's largest
/// extent). The surface must have a finite bounding box.
pub fn enclosure<S: MeanSurface>(surface: &S, level: f64, cell: f64) -> Result<Enclosure> {
    let invalid = |m: String| Error::new(ErrorKind::InvalidArgument, m);
    if !level.is_finite() {
        return Err(invalid(format!("level must be finite, got {level}")));
    }
    if !(cell >= 0.0 && cell.is_finite()) {
        return Err(invalid(format!("cell size must be finite and >= 0, got {cell}")));
    }
    let bounds = surface.bounding_box();
    if !(bounds.min.is_finite() && bounds.max.is_finite()) {
        return Err(invalid("the surface is unbounded: an enclosure needs a finite bounding box".into()));
    }
    // The region lies within `level` of the box (f is a signed distance); one cell of margin
    // keeps the enclosure off the region's boundary.
    let extent = (bounds.max - bounds.min).max_element().max(level.abs()).max(f64::MIN_POSITIVE);
    let mut h = if cell > 0.0 { cell } else { extent / 128.0 };
    let grow = level.max(0.0) + h;
    let (lo, hi) = (bounds.min - DVec3::splat(grow), bounds.max + DVec3::splat(grow));
    if (hi - lo).max_element() / h > MAX_CELLS {
        h = (hi - lo).max_element() / MAX_CELLS;
    }
    let half_diagonal = 0.5 * 3f64.sqrt() * h;
    // Cells are kept up to a hair above the level, so that every point of the region lies at
    // least 1e-3 cells inside the enclosure: safe from the rounding of hosts' f32 vertices.
    let level = level + 1e-3 * h;
    let blocks = ((hi - lo) / (h * BLOCK as f64)).ceil().as_ivec3().max(IVec3::ONE);
    let cells = blocks * BLOCK;

    // Kept cells, by a descent through blocks halving down to cells: one query at a block's
    // centre decides it whole when `f` there is at least half its diagonal from the level.
    let mut kept = vec![false; (cells.x * cells.y * cells.z) as usize];
    let index = |c: IVec3| ((c.z * cells.y + c.y) * cells.x + c.x) as usize;
    let mut stack: Vec<(IVec3, i32)> = Vec::new();
    for bz in 0..blocks.z {
        for by in 0..blocks.y {
            for bx in 0..blocks.x {
                stack.push((IVec3::new(bx, by, bz) * BLOCK, BLOCK));
            }
        }
    }
    // Depth first, so that consecutive queries are close: the surface may reuse the last one.
    let mut cache = S::Cache::default();
    while let Some((first, size)) = stack.pop() {
        let block_centre = lo + (first.as_dvec3() + 0.5 * size as f64) * h;
        let f = surface.start_point(block_centre, &mut cache)?.validated(block_centre)?.f;
        if size == 1 {
            kept[index(first)] = f - half_diagonal < level;
            continue;
        }
        let block_half_diagonal = half_diagonal * size as f64;
        // Every cell centre has f >= level + half a cell diagonal: none kept.
        if f - block_half_diagonal >= level + half_diagonal {
            continue;
        }
        if f + block_half_diagonal < level - half_diagonal {
            for z in 0..size {
                for y in 0..size {
                    for x in 0..size {
                        kept[index(first + IVec3::new(x, y, z))] = true;
                    }
                }
            }
            continue;
        }
        let half = size / 2;
        for z in 0..2 {
            for y in 0..2 {
                for x in 0..2 {
                    stack.push((first + IVec3::new(x, y, z) * half, half));
                }
            }
        }
    }

    // The faces between kept and dropped cells (outside the grid counts as dropped).
    let is_kept = |c: IVec3| c.cmpge(IVec3::ZERO).all() && c.cmplt(cells).all() && kept[index(c)];
    let mut out = Enclosure { cell: h, ..Default::default() };
    let mut vertex: HashMap<IVec3, u32> = HashMap::new();
    let mut corner = |g: IVec3, out: &mut Enclosure| -> u32 {
        *vertex.entry(g).or_insert_with(|| {
            out.positions.push(lo + g.as_dvec3() * h);
            (out.positions.len() - 1) as u32
        })
    };
    for z in 0..cells.z {
        for y in 0..cells.y {
            for x in 0..cells.x {
                let c = IVec3::new(x, y, z);
                if !kept[index(c)] {
                    continue;
                }
                for axis in 0..3 {
                    for side in [-1, 1] {
                        let mut step = IVec3::ZERO;
                        step[axis] = side;
                        if is_kept(c + step) {
                            continue;
                        }
                        // The face's corners, counter-clockwise seen from outside (along +side).
                        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                        let mut base = c;
                        if side > 0 {
                            base[axis] += 1;
                        }
                        let (mut du, mut dv) = (IVec3::ZERO, IVec3::ZERO);
                        du[u] = 1;
                        dv[v] = 1;
                        let quad = [base, base + du, base + du + dv, base + dv].map(|g| corner(g, &mut out));
                        if side > 0 {
                            out.triangles.push([quad[0], quad[1], quad[2]]);
                            out.triangles.push([quad[0], quad[2], quad[3]]);
                        } else {
                            out.triangles.push([quad[0], quad[2], quad[1]]);
                            out.triangles.push([quad[0], quad[3], quad[2]]);
                        }
                    }
                }
            }
        }
    }
    if out.triangles.is_empty() {
        return Err(invalid(format!("the region f < {level} is empty")));
    }
    Ok(out)
}
