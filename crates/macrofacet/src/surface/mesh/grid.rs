//! A narrow-band grid of candidate lists: for every cell near the surface, the triangles that
//! can be closest to some point of the cell. Most queries of a thin shell fall into such a cell,
//! where the closest point is found among a handful of triangles instead of by a hierarchy
//! search, and a segment's candidates are the union of the lists of the cells it crosses.
//!
//! A cell's list: with `c` its centre, `r` its half diagonal and `d` the distance from `c` to the
//! mesh, every point `x` of the cell has its closest triangle within `d + r` of `x`, hence within
//! `d + 2r` of `c`; the list holds every triangle within that distance (with a relative margin for
//! rounding, so it also serves points a hair outside the cell). A mesh built for a reach
//! ([`super::TriangleMesh::new`]) needs the lists only for the points within its covered
//! distance `ρ` of the mesh, whose closest triangle lies within `ρ + r` of `c`: the lists stop
//! there too, and an answer farther than `ρ` is left to the hierarchy ([`CellGrid::covered`]).

use super::bvh::Bvh;
use super::triangle::{closest_on_triangle, Closest, Triangle};
use crate::ordered::less;
use crate::parallel;
use glam::{DVec3, IVec3};

/// Cells whose centre is farther than this many cells from the surface get no list (queries
/// there use the hierarchy), nor those farther than half a diagonal beyond the mesh's covered
/// distance (every point within that distance of the mesh still lies in a cell with a list).
const BAND_CELLS: f64 = 1.5;
/// Fine cells per edge of the coarsest blocks of the build (a power of two: they halve down to
/// cells where they meet the band).
const BLOCK: i32 = 8;
/// The most cells; beyond, the cells grow.
const MAX_CELLS: f64 = 2.0e6;
/// Longer lists are dropped (queries there use the hierarchy).
const MAX_LIST: usize = 32;

/// A union of cell lists: room for a few cells' lists on the stack (a tracking call's cache
/// starts empty, and a `Vec` allocated and grew in most calls through a mesh: 3.5 allocations
/// per call on the thin torus anchor).
pub(super) type Lists = smallvec::SmallVec<[u32; 4 * MAX_LIST]>;

#[derive(Clone, Debug)]
pub(super) struct CellGrid {
    origin: DVec3,
    h: f64,
    dims: IVec3,
    /// `lists[offsets[i]..offsets[i + 1]]` is cell `i`'s list; empty outside the band.
    offsets: Vec<u32>,
    lists: Vec<u32>,
    /// A lower bound of the distance to the mesh over each cell (rounded down to f32).
    lower: Vec<f32>,
    /// The lists hold the closest triangle of every point of their cell within this of the mesh
    /// (`+∞`: of every point).
    covered: f64,
}

impl CellGrid {
    /// The grid over the mesh's bounds (`min`, `max`) with cells of about `cell` and lists for
    /// the points within `covered` of the mesh, on up to `threads` threads (one block of the
    /// coarsest level at a time each).
    pub fn build(bvh: &Bvh, triangles: &[Triangle], min: DVec3, max: DVec3, cell: f64, covered: f64, threads: usize) -> CellGrid {
        let extent = max - min;
        let mut h = cell.max((extent.x * extent.y * extent.z / MAX_CELLS).cbrt()).max(1e-12 * extent.max_element());
        // Blocks per axis with the band's padding; a flat mesh (no volume) of small triangles
        // would otherwise get ~1e12 cells per axis: grow the cells until the count is bounded.
        let blocks_of = |h: f64| ((extent + 2.0 * (BAND_CELLS + 1.0) * h) / (h * BLOCK as f64)).ceil().max(DVec3::ONE);
        while blocks_of(h).element_product() * f64::from(BLOCK.pow(3)) > 4.0 * MAX_CELLS {
            h *= 1.25;
        }
        let half_diagonal = 0.5 * 3f64.sqrt() * h;
        let band = (BAND_CELLS * h).min(half_diagonal + covered);
        let origin = min - DVec3::splat(BAND_CELLS * h + h);
        let blocks = blocks_of(h).as_ivec3();
        let dims = blocks * BLOCK;
        let count = (dims.x as usize) * (dims.y as usize) * (dims.z as usize);
        let index = |c: IVec3| ((c.z * dims.y + c.y) * dims.x + c.x) as usize;
        let block_of = |b: usize| {
            let (x, y) = (b as i32 % blocks.x, b as i32 / blocks.x);
            IVec3::new(x, y % blocks.y, y / blocks.y) * BLOCK
        };
        let built = parallel::map(blocks.element_product() as usize, threads, Vec::new, |near, b| {
            descend(bvh, triangles, block_of(b), Level { origin, h, band, half_diagonal, covered }, near)
        });
        let mut lists_of: Vec<Vec<u32>> = vec![Vec::new(); count];
        let mut lower = vec![0f32; count];
        for (b, block) in built.into_iter().enumerate() {
            let first = block_of(b);
            for (k, bound) in block.lower.iter().enumerate() {
                lower[index(first + local(k))] = *bound;
            }
            for (k, list) in block.lists {
                lists_of[index(first + local(usize::from(k)))] = list;
            }
        }
        let mut offsets = Vec::with_capacity(count + 1);
        let mut lists = Vec::new();
        offsets.push(0);
        for l in &lists_of {
            lists.extend_from_slice(l);
            offsets.push(lists.len() as u32);
        }
        CellGrid { origin, h, dims, offsets, lists, lower, covered }
    }

    /// The distance from the mesh within which the lists are complete: a closest triangle found
    /// in a cell's list ([`Self::list_at`]) or a segment's ([`Self::segment`]) at most this far
    /// from the point is the mesh's.
    pub fn covered(&self) -> f64 {
        self.covered
    }

    /// A lower bound of the distance from `p` to the mesh (0 outside the grid).
    pub fn distance_bound(&self, p: DVec3) -> f64 {
        match self.cell_of(p) {
            Some(c) => f64::from(self.lower[((c.z * self.dims.y + c.y) * self.dims.x + c.x) as usize]),
            None => 0.0,
        }
    }

    fn cell_of(&self, p: DVec3) -> Option<IVec3> {
        // Truncation, once inside: the floor there, without `floor` (a library call on baseline
        // x86-64, 0.8 % of a mesh shell's rendering). `c >= 0` and `c < dims` are those of the
        // floor, the dims being whole; NaN fails both.
        let c = (p - self.origin) / self.h;
        (c.cmpge(DVec3::ZERO).all() && c.cmplt(self.dims.as_dvec3()).all()).then(|| c.as_ivec3())
    }

    fn list(&self, c: IVec3) -> &[u32] {
        let i = ((c.z * self.dims.y + c.y) * self.dims.x + c.x) as usize;
        &self.lists[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }

    /// The list of the cell of `p`, nearest to its centre first; `None` outside the band. It holds
    /// `p`'s closest triangle where that lies within [`Self::covered`] of `p`.
    pub fn list_at(&self, p: DVec3) -> Option<&[u32]> {
        let list = self.list(self.cell_of(p)?);
        (!list.is_empty()).then_some(list)
    }

    /// The union of the lists of every cell the segment `p + s d`, `s ∈ [0, length]`, crosses
    /// (3-D DDA, Amanatides & Woo 1987), or `false` when it leaves the band. It holds the closest
    /// triangle of each point of the segment within [`Self::covered`] of the mesh.
    pub fn segment(&self, p: DVec3, d: DVec3, length: f64, out: &mut Lists) -> bool {
        out.clear();
        let Some(mut c) = self.cell_of(p) else { return false };
        // A segment that ends outside the band leaves it: known before walking its cells (in a
        // thick shell most segments start inside the band and end outside, where the walk
        // gathered lists only to drop them; 1.2 % of the volume-like torus's rendering).
        if self.list_at(p + length * d).is_none() {
            return false;
        }
        let step = IVec3::new(sign(d.x), sign(d.y), sign(d.z));
        let rel = (p - self.origin) / self.h;
        // Parameter of the next cell boundary along each axis, and between boundaries.
        let mut next = DVec3::ZERO;
        let mut delta = DVec3::ZERO;
        for a in 0..3 {
            if step[a] == 0 {
                next[a] = f64::INFINITY;
                delta[a] = f64::INFINITY;
            } else {
                let boundary = if step[a] > 0 { c[a] as f64 + 1.0 } else { c[a] as f64 };
                next[a] = (boundary - rel[a]) * self.h / d[a];
                delta[a] = self.h / d[a].abs();
            }
        }
        loop {
            let list = self.list(c);
            if list.is_empty() {
                return false;
            }
            out.extend_from_slice(list);
            let a = if next.x <= next.y && next.x <= next.z { 0 } else if next.y <= next.z { 1 } else { 2 };
            if next[a] > length {
                break;
            }
            c[a] += step[a];
            if c[a] < 0 || c[a] >= self.dims[a] {
                return false;
            }
            next[a] += delta[a];
        }
        sort_distinct(out);
        true
    }
}

/// Slots of [`drop_repeats`]'s table (a power of two; 1 KiB on the stack).
const DISTINCT_SLOTS: usize = 256;

/// Unions up to this long are sorted as they are: below it [`drop_repeats`]'s 1 KiB cost more than
/// the repeats (the torus anchor's thin shell ran 0.2 % more instructions with the table for all).
const SHORT_UNION: usize = 64;

/// Where [`drop_repeats`] first looks for `x`: Fibonacci hashing, the top bits of `x` times
/// `2^32/φ`.
#[inline]
fn distinct_slot(x: u32) -> usize {
    (x.wrapping_mul(0x9E37_79B9) >> (32 - DISTINCT_SLOTS.trailing_zeros())) as usize
}

/// `v` sorted with its repeats removed (`sort_unstable` and `dedup`). A segment's union repeats
/// most triangles (neighbouring cells share them): a long one drops its repeats first
/// ([`drop_repeats`]), so that only the distinct ones are sorted (sorting ~150 entries, most of
/// them repeats, was 6 % of a thin mesh shell's rendering).
fn sort_distinct(v: &mut Lists) {
    if v.len() > SHORT_UNION {
        drop_repeats(v);
    }
    v.sort_unstable();
    v.dedup();
}

/// Drops the repeats of `v` through an open-addressing table, keeping each value's first
/// occurrence in place of the entries already read. With more than half the table's slots
/// taken it stops, `v` still holding every value (the entries before the current one are kept
/// values or repeats of them, the rest unread).
fn drop_repeats(v: &mut Lists) {
    const EMPTY: u32 = u32::MAX; // never a triangle: indices are below the triangle count
    let mut table = [EMPTY; DISTINCT_SLOTS];
    let mut kept = 0;
    for k in 0..v.len() {
        let x = v[k];
        let mut slot = distinct_slot(x);
        loop {
            if table[slot] == x {
                break;
            }
            if table[slot] == EMPTY {
                table[slot] = x;
                // (kept <= k: the entries overwritten were read already.)
                v[kept] = x;
                kept += 1;
                break;
            }
            slot = (slot + 1) & (DISTINCT_SLOTS - 1);
        }
        if 2 * kept > DISTINCT_SLOTS {
            return;
        }
    }
    v.truncate(kept);
}

fn sign(x: f64) -> i32 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

/// The grid's geometry, as the descent needs it.
#[derive(Clone, Copy)]
struct Level {
    origin: DVec3,
    /// The cells' edge.
    h: f64,
    /// Cells whose centre lies within this of the mesh get a list.
    band: f64,
    /// A cell's half diagonal.
    half_diagonal: f64,
    /// The distance from the mesh within which the lists must be complete.
    covered: f64,
}

/// One block of the coarsest level: its cells' distance bounds (`BLOCK³`, x fastest) and the
/// lists of its cells in the band (by their index in the block).
struct Block {
    lower: Vec<f32>,
    lists: Vec<(u16, Vec<u32>)>,
}

/// Cell `k` of a block, from its first cell (x fastest).
fn local(k: usize) -> IVec3 {
    let k = k as i32;
    IVec3::new(k % BLOCK, (k / BLOCK) % BLOCK, k / (BLOCK * BLOCK))
}

/// The descent through one coarsest block (its first cell `first`), halving down to cells: a
/// block whose centre is farther than the band plus the distance to its farthest cell's centre
/// holds no band cell (a cell is in the band by its centre's distance), and bounds its cells'
/// distances. `near`: scratch space.
fn descend(bvh: &Bvh, triangles: &[Triangle], first: IVec3, level: Level, near: &mut Vec<(f64, u32)>) -> Block {
    let Level { origin, h, band, half_diagonal, covered } = level;
    let mut out = Block { lower: vec![0f32; (BLOCK * BLOCK * BLOCK) as usize], lists: Vec::new() };
    let slot = |c: IVec3| {
        let k = c - first;
        ((k.z * BLOCK + k.y) * BLOCK + k.x) as usize
    };
    // Rounded toward zero so that the f32 stays a lower bound.
    let bound = |x: f64| -> f32 {
        let y = x.max(0.0) as f32;
        if f64::from(y) > x.max(0.0) { f32::from_bits(y.to_bits().saturating_sub(1)) } else { y }
    };
    // A cell's list holds the triangles within this of its centre, `d` the centre's distance:
    // the closest of any point of the cell, or of one within `covered` of the mesh.
    let reach_of = |d: f64| (d.min(covered - half_diagonal) + 2.0 * half_diagonal) * (1.0 + 1e-9) + 1e-12 * h;
    // Where the covered distance limits every list to about the band (a mesh built for a thin
    // shell: `covered − r <= band`), a cell's one radius query out to the band's reach also finds
    // its centre's distance (the closest triangle lies within it when the cell is in the band),
    // in place of the closest-point search: a thin shell's grid builds with 29 % fewer
    // instructions. Elsewhere the reach grows with the distance, and the search comes first.
    let band_reach = reach_of(band);
    let one_query = covered - half_diagonal <= band;
    // Each block by its first cell (`corner`) and size, with the triangle closest to its parent's
    // centre: it seeds the search.
    let mut stack: Vec<(IVec3, i32, Option<u32>)> = vec![(first, BLOCK, None)];
    while let Some((corner, size, seed)) = stack.pop() {
        let block_centre = origin + (corner.as_dvec3() + 0.5 * size as f64) * h;
        if size == 1 && one_query && bvh.within_distances(triangles, block_centre, band_reach, MAX_LIST, near) {
            let d = near.iter().map(|&(distance_sq, _)| distance_sq).fold(f64::INFINITY, less).sqrt();
            // Nothing within the band's reach: the distance exceeds it.
            out.lower[slot(corner)] = bound((less(d, band_reach) - half_diagonal) * (1.0 - 1e-9));
            if d <= band {
                let reach_sq = reach_of(d) * reach_of(d);
                near.retain(|&(distance_sq, _)| distance_sq <= reach_sq);
                out.lists.push((slot(corner) as u16, cell_list(triangles, corner, origin, h, d, half_diagonal, covered, near)));
            }
            continue;
        }
        let seed = seed.map_or(Closest::NONE, |i| closest_on_triangle(&triangles[i as usize], block_centre, i));
        let nearest = bvh.closest(triangles, block_centre, seed);
        let d_block = nearest.distance_sq.sqrt();
        // Its cells' centres lie within (size − 1) cell half diagonals of its centre.
        let farthest_centre = half_diagonal * (size - 1) as f64;
        if size > 1 && d_block - farthest_centre > band {
            // Every point of a cell is at least d_block minus its distance from the centre.
            for z in 0..size {
                for y in 0..size {
                    for x in 0..size {
                        let c = corner + IVec3::new(x, y, z);
                        let farthest = (origin + (c.as_dvec3() + 0.5) * h - block_centre).length() + half_diagonal;
                        out.lower[slot(c)] = bound((d_block - farthest) * (1.0 - 1e-9));
                    }
                }
            }
            continue;
        }
        if size > 1 {
            let half = size / 2;
            for z in 0..2 {
                for y in 0..2 {
                    for x in 0..2 {
                        stack.push((corner + IVec3::new(x, y, z) * half, half, Some(nearest.triangle)));
                    }
                }
            }
            continue;
        }
        let (c, centre, d) = (corner, block_centre, d_block);
        out.lower[slot(c)] = bound((d - half_diagonal) * (1.0 - 1e-9));
        if d > band {
            continue;
        }
        if bvh.within_distances(triangles, centre, reach_of(d), MAX_LIST, near) {
            out.lists.push((slot(c) as u16, cell_list(triangles, c, origin, h, d, half_diagonal, covered, near)));
        }
    }
    out
}

/// Cell `c`'s list from the triangles within its reach (`candidates`: `(distance², index)` from
/// the cell's centre, in any order: [`Bvh::within_distances`]), `d` the centre's distance to the
/// mesh: those that can come within `d + r` (the farthest any cell point is from the mesh), or
/// `covered` if less, of the cell, by the distance between bounding boxes and the distance from
/// the triangle's plane (both bound the distance to the cell from below), nearest to the centre
/// first (queries start from it; ties by index).
#[allow(clippy::too_many_arguments)]
fn cell_list(triangles: &[Triangle], c: IVec3, origin: DVec3, h: f64, d: f64, half_diagonal: f64, covered: f64, candidates: &[(f64, u32)]) -> Vec<u32> {
    let (lo, hi) = (origin + c.as_dvec3() * h, origin + (c.as_dvec3() + 1.0) * h);
    let centre = origin + (c.as_dvec3() + 0.5) * h;
    let limit = (d + half_diagonal).min(covered) * (1.0 + 1e-9) + 1e-12 * h;
    let mut kept: Vec<(u64, u32)> = Vec::with_capacity(candidates.len());
    for &(distance_sq, i) in candidates {
        let t = &triangles[i as usize];
        let (tlo, thi) = (t.p[0].min(t.p[1]).min(t.p[2]), t.p[0].max(t.p[1]).max(t.p[2]));
        let gap = (tlo - hi).max(lo - thi).max(DVec3::ZERO).length();
        let plane = (t.n.dot(centre - t.p[0]).abs() - 0.5 * h * t.n.abs().element_sum()).max(0.0);
        if gap.max(plane) <= limit {
            kept.push((distance_sq.to_bits(), i));
        }
    }
    kept.sort_unstable();
    kept.into_iter().map(|(_, i)| i).collect()
}

#[cfg(test)]
mod tests {
    use super::{distinct_slot, sort_distinct, Lists, DISTINCT_SLOTS};
    use crate::rng::Pcg32;

    #[test]
    fn sort_distinct_equals_sort_and_dedup() {
        let mut rng = Pcg32::new(3, 5);
        // Few distinct values repeated (a segment's union), many distinct ones (past half the
        // table: the plain sort), values that collide in the table, and the empty list.
        for (len, range) in [(0, 1), (1, 10), (150, 40), (400, 60), (300, 5000), (2 * DISTINCT_SLOTS, 200), (1000, 3_000_000)] {
            for _ in 0..20 {
                let v: Vec<u32> = (0..len).map(|_| (rng.next_f64() * range as f64) as u32).collect();
                let mut want = v.clone();
                want.sort_unstable();
                want.dedup();
                let mut got = Lists::from_slice(&v);
                sort_distinct(&mut got);
                assert_eq!(got.as_slice(), want.as_slice(), "len {len}, values below {range}");
            }
        }
        // Values that all hash to one slot probe one long run of slots.
        let same: Vec<u32> = (0..200_000u32).filter(|&x| distinct_slot(x) == distinct_slot(0)).take(60).collect();
        assert_eq!(same.len(), 60);
        let mut v: Lists = (0..300).map(|i| same[(i * 7) % same.len()]).collect();
        let mut want = v.to_vec();
        want.sort_unstable();
        want.dedup();
        sort_distinct(&mut v);
        assert_eq!(v.as_slice(), want.as_slice());
    }
}
