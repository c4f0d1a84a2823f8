//! A closed triangle mesh that encloses the region `f < level` of a mean surface: what a host
//! puts into its ray tracer as the boundary of a macrofacet medium (the shell's top face is the
//! level `k σ`), so that no ray ever sphere-traces the level set.
//!
//! Built from cubes of a grid: a cell is kept when it may meet the region, which the Lipschitz
//! bound decides from one query at its centre (`f(x) >= f(c) − L |x − c|`, `L = 1` for a signed
//! distance, [`MeanSurface::lipschitz`]), and the enclosure is the boundary between kept and
//! dropped cells. It is therefore conservative by construction (no point of the region lies
//! outside it), watertight and free of self-intersections; it lies within `L` cell diagonals of
//! the level set. Blocks of cells are halved only where the same
//! bound at their centre leaves them undecided, so the queries follow the level set.
//!
//! With the default cell, a surface that can build a tighter enclosure and prove it
//! conservative gives that instead ([`MeanSurface::offset_enclosure`]): a triangle mesh's own
//! faces moved out along its vertex normals (`mesh/offset.rs`), which lies within about
//! `level / cos θ` of the level set rather than a cell diagonal (the thin torus anchor: 3,072
//! triangles whose vertices lie within 1e-4 of the shell's top, instead of 101,360 within 0.038).

use super::MeanSurface;
use crate::error::{Error, ErrorKind, Result};
use crate::limits::SIGMA_RANGE;
use glam::{DVec3, IVec3};

/// Fine cells per coarse block edge (a power of two: blocks halve down to cells).
const BLOCK: i32 = 8;
const _: () = assert!(BLOCK > 0 && BLOCK & (BLOCK - 1) == 0, "BLOCK must be a power of two");
/// The largest grid, in fine cells along the longest axis (the cell grows beyond it); 128 when
/// built for fuzzing (`cfg(fuzzing)`): a 512-cell enclosure takes up to 0.5 s, a third of a
/// fuzzer's time at one call in 32 executions.
const MAX_CELLS: f64 = if cfg!(fuzzing) { 128.0 } else { 512.0 };
/// The smallest cell, in ulps of the largest coordinate (the cell grows below it).
const MIN_CELL_ULPS: f64 = 1e5;
/// The smallest cell at all: 1e-3 of the smallest `sigma` ([`SIGMA_RANGE`]), far above where
/// squared distances underflow (~1e-154).
const MIN_CELL: f64 = 1e-3 * SIGMA_RANGE.0;
/// The default cell is at least this fraction of a positive level: the enclosure of a thick
/// shell then lies within about a fifth of its top (`√3 / 8`), which is all a ray needs to find
/// it, and its build and mesh shrink with the cells (the default scene's volume-like and
/// in-between tori: 2.4 G fewer instructions to build, 16 % of the scene's build, for 0.5 %
/// more in rendering, where rays cross the wider gap in steps of `f − top`).
const LEVEL_CELLS: f64 = 8.0;

/// A triangle mesh: positions and counter-clockwise (seen from outside) triangles.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Enclosure {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
    /// The cell size used.
    pub cell: f64,
    /// A level of `f` that no point the enclosure encloses exceeds, nor any point within
    /// single-precision rounding of it (a host's `f32` copy of the vertices, and of a ray's
    /// origin): above it a ray has left the region ([`crate::tracking::Tracker::sample_free_flight_to_exit`]).
    /// A kept cell's centre lies below the level plus half a cell diagonal, so its corners below
    /// the level plus a diagonal; an offset face's points lie within the largest vertex offset
    /// of their mesh face (`mesh/offset.rs`).
    pub exit_level: f64,
}

/// The enclosure of `f < level` with cells of about `cell` (0: the surface's own offset
/// enclosure where it has one, [`MeanSurface::offset_enclosure`], with `cell = 0` in the result;
/// else 1/128 of the surface's largest extent, or 1/8 of a larger level: `LEVEL_CELLS`). The
/// surface must have a finite bounding box.
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
    // The default cell asks for the tightest enclosure: the surface's own where it has one.
    if cell == 0.0 {
        if let Some(offset) = surface.offset_enclosure(level) {
            return Ok(offset);
        }
    }
    // The region lies within `level` of the box (f is a signed distance); one cell of margin
    // keeps the enclosure off the region's boundary.
    let extent = (bounds.max - bounds.min).max_element().max(level.abs()).max(f64::MIN_POSITIVE);
    // Vertices `lo + g h` are rounded by a few ulps of the coordinates: cells of at least
    // MIN_CELL_ULPS of them keep that rounding within 1/50 of the hair below (found by fuzzing:
    // a sphere of radius 6e-36 at (0, 1, 2), where the cells were below an ulp).
    // Nor below MIN_CELL, where the surface's squared distances underflow (found by fuzzing:
    // a point-like sphere with cells of 7e-310 answered f = 0 at every corner).
    let magnitude = bounds.min.abs().max(bounds.max.abs()).max_element() + level.max(0.0);
    let mut h = (if cell > 0.0 { cell } else { (extent / 128.0).max(level.max(0.0) / LEVEL_CELLS) }).max(MIN_CELL_ULPS * f64::EPSILON * magnitude).max(MIN_CELL);
    let grow = level.max(0.0) + h;
    let (lo, hi) = (bounds.min - DVec3::splat(grow), bounds.max + DVec3::splat(grow));
    if (hi - lo).max_element() / h > MAX_CELLS {
        h = (hi - lo).max_element() / MAX_CELLS;
    }
    // Half a cell diagonal, times the Lipschitz constant: how much f can change from a cell's
    // centre to its corners.
    let half_diagonal = 0.5 * 3f64.sqrt() * h * surface.lipschitz();
    // Cells are kept up to a hair above the level, so that every point of the region lies at
    // least 1e-3 cells inside the enclosure: safe from the rounding of the vertices, and of a
    // host's f32 copy of them while the cells exceed 1e-4 of the coordinates (the default cell
    // of a surface near the origin is 1/128 of its size).
    let level = level + 1e-3 * h * surface.lipschitz();
    // Every corner `lo + g h` must be a number, and so must its offset `g h` (found by fuzzing:
    // level −1e308 with cells of 1e308 made the grid's extent overflow, and the vertices NaN; a
    // box from −1e308 to −2 with cells of 1.4e307 had `g h` = inf at the far corner, which lies
    // at 1.2e308).
    let out_of_range = || invalid(format!("the enclosure's grid (cells of {h:e} around the surface's box grown by {grow:e} for level {level:e}) exceeds the range of f64"));
    if !(hi - lo).is_finite() {
        return Err(out_of_range());
    }
    let blocks = ((hi - lo) / (h * BLOCK as f64)).ceil().as_ivec3().max(IVec3::ONE);
    let cells = blocks * BLOCK;
    let far_offset = cells.as_dvec3() * h;
    if !(far_offset.is_finite() && (lo + far_offset).is_finite()) {
        return Err(out_of_range());
    }

    // Kept cells, by a descent through blocks halving down to cells: one query at a block's
    // centre decides it whole when `f` there is at least half its diagonal from the level.
    // Whole blocks stay whole and only blocks the level set crosses keep a bit per cell, so time
    // and memory follow the level set's area rather than the grid's volume.
    let mut kept = Kept::new(blocks);
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
            if f - half_diagonal < level {
                kept.insert(first, 1);
            }
            continue;
        }
        let block_half_diagonal = half_diagonal * size as f64;
        // Every cell centre has f >= level + half a cell diagonal: none kept.
        if f - block_half_diagonal >= level + half_diagonal {
            continue;
        }
        if f + block_half_diagonal < level - half_diagonal {
            kept.insert(first, size);
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

    // The faces between kept and dropped cells (outside the grid counts as dropped), each as a
    // key in the order of a scan of the grid (z, y, x, axis, side), so that the mesh does not
    // depend on the order in which they are found. 512³ cells × 6 faces fit in a u32.
    let is_kept = |c: IVec3| c.cmpge(IVec3::ZERO).all() && c.cmplt(cells).all() && kept.contains(c);
    let face_key = |c: IVec3, axis: usize, side: i32| ((((c.z * cells.y + c.y) * cells.x + c.x) as u32) * 3 + axis as u32) * 2 + u32::from(side > 0);
    let step = |axis: usize, side: i32| {
        let mut step = IVec3::ZERO;
        step[axis] = side;
        step
    };
    let mut faces: Vec<u32> = Vec::new();
    let mut face_if_open = |c: IVec3, axis: usize, side: i32| {
        if !is_kept(c + step(axis, side)) {
            faces.push(face_key(c, axis, side));
        }
    };
    for bz in 0..blocks.z {
        for by in 0..blocks.y {
            for bx in 0..blocks.x {
                let block = IVec3::new(bx, by, bz);
                let first = block * BLOCK;
                match kept.block(block) {
                    BlockCells::None => {}
                    BlockCells::All => {
                        // Only the cells on faces whose neighbouring block is not whole.
                        for axis in 0..3 {
                            for side in [-1, 1] {
                                let across = block + step(axis, side);
                                if across.cmpge(IVec3::ZERO).all() && across.cmplt(blocks).all() && matches!(kept.block(across), BlockCells::All) {
                                    continue;
                                }
                                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                                for i in 0..BLOCK {
                                    for j in 0..BLOCK {
                                        let mut c = first;
                                        c[u] += i;
                                        c[v] += j;
                                        if side > 0 {
                                            c[axis] += BLOCK - 1;
                                        }
                                        face_if_open(c, axis, side);
                                    }
                                }
                            }
                        }
                    }
                    BlockCells::Some(bits) => {
                        for (word, &w) in bits.iter().enumerate() {
                            let mut w = w;
                            while w != 0 {
                                let bit = word as i32 * 64 + w.trailing_zeros() as i32;
                                w &= w - 1;
                                for axis in 0..3 {
                                    for side in [-1, 1] {
                                        face_if_open(first + Kept::cell_of_bit(bit), axis, side);
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    faces.sort_unstable();
    // The hair above the level is in `level` already; another covers the vertices' rounding.
    let exit_level = level + (2.0 * half_diagonal + 1e-3 * h * surface.lipschitz());
    let mut out = Enclosure { cell: h, exit_level, ..Default::default() };
    // A corner's vertex, numbered in order of first use. The faces come in increasing z, and a
    // face's corners lie on its cell's two z planes, so two planes of ids (by parity of z, each
    // entry stamped with its z) remember every corner that can still be shared.
    let plane = ((cells.x + 1) * (cells.y + 1)) as usize;
    let mut vertex: Vec<(i32, u32)> = vec![(-1, 0); 2 * plane];
    let mut corner = |g: IVec3, out: &mut Enclosure| -> u32 {
        let slot = &mut vertex[(g.z & 1) as usize * plane + (g.y * (cells.x + 1) + g.x) as usize];
        if slot.0 != g.z {
            out.positions.push(lo + g.as_dvec3() * h);
            *slot = (g.z, (out.positions.len() - 1) as u32);
        }
        slot.1
    };
    for key in faces {
        let (side, axis, cell) = (if key % 2 == 1 { 1 } else { -1 }, (key / 2 % 3) as usize, (key / 6) as i32);
        let c = IVec3::new(cell % cells.x, cell / cells.x % cells.y, cell / (cells.x * cells.y));
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
    if out.triangles.is_empty() {
        return Err(invalid(format!("the region f < {level} is empty")));
    }
    Ok(out)
}

/// The kept cells of the grid, by block of `BLOCK³` cells: none, all, or some (a bit per cell).
struct Kept {
    blocks: IVec3,
    /// Per block: [`NONE`](Kept::NONE), [`ALL`](Kept::ALL), or `SOME + i` for `bits[i]`.
    state: Vec<u32>,
    bits: Vec<[u64; BLOCK_WORDS]>,
}

/// 64-bit words per block of `BLOCK³` cells.
const BLOCK_WORDS: usize = (BLOCK * BLOCK * BLOCK) as usize / 64;

/// The kept cells of one block.
enum BlockCells<'a> {
    None,
    All,
    Some(&'a [u64; BLOCK_WORDS]),
}

impl Kept {
    const NONE: u32 = 0;
    const ALL: u32 = 1;
    const SOME: u32 = 2;

    fn new(blocks: IVec3) -> Self {
        Kept { blocks, state: vec![Self::NONE; (blocks.x * blocks.y * blocks.z) as usize], bits: Vec::new() }
    }

    fn block_index(&self, block: IVec3) -> usize {
        ((block.z * self.blocks.y + block.y) * self.blocks.x + block.x) as usize
    }

    fn bit_of_cell(local: IVec3) -> i32 {
        (local.z * BLOCK + local.y) * BLOCK + local.x
    }

    fn cell_of_bit(bit: i32) -> IVec3 {
        IVec3::new(bit % BLOCK, bit / BLOCK % BLOCK, bit / (BLOCK * BLOCK))
    }

    /// Keeps the aligned cube of `size³` cells at `first` (inside one block).
    fn insert(&mut self, first: IVec3, size: i32) {
        let block = first.div_euclid(IVec3::splat(BLOCK));
        let index = self.block_index(block);
        if size == BLOCK {
            self.state[index] = Self::ALL;
            return;
        }
        if self.state[index] == Self::NONE {
            self.state[index] = Self::SOME + self.bits.len() as u32;
            self.bits.push([0; BLOCK_WORDS]);
        }
        let words = &mut self.bits[(self.state[index] - Self::SOME) as usize];
        let local = first - block * BLOCK;
        for z in 0..size {
            for y in 0..size {
                for x in 0..size {
                    let bit = Self::bit_of_cell(local + IVec3::new(x, y, z));
                    words[(bit / 64) as usize] |= 1 << (bit % 64);
                }
            }
        }
    }

    fn block(&self, block: IVec3) -> BlockCells<'_> {
        match self.state[self.block_index(block)] {
            Self::NONE => BlockCells::None,
            Self::ALL => BlockCells::All,
            i => BlockCells::Some(&self.bits[(i - Self::SOME) as usize]),
        }
    }

    /// Whether the cell `c` (inside the grid) is kept.
    fn contains(&self, c: IVec3) -> bool {
        // Inside the grid c >= 0, and BLOCK is a power of two: a shift, where `div_euclid`'s
        // general division was 5 % of the default scene's build (every face of every kept cell
        // asks for its neighbour).
        debug_assert!(c.cmpge(IVec3::ZERO).all());
        let block = c >> BLOCK.trailing_zeros() as i32;
        match self.block(block) {
            BlockCells::None => false,
            BlockCells::All => true,
            BlockCells::Some(words) => {
                let bit = Self::bit_of_cell(c - block * BLOCK);
                words[(bit / 64) as usize] >> (bit % 64) & 1 == 1
            }
        }
    }
}
