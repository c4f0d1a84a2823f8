//! A signed-distance grid as a mean surface (Mitsuba 3's `sdfgrid`; seeds/004 Sec. 6.1.1 stores
//! the mean on a voxel grid): samples at the corners of a regular grid over the unit cube of
//! object space, trilinearly interpolated, placed in the world by a similarity transform (so the
//! values, in object units, scale to world distances). The frame normal is the normalised
//! gradient of the interpolant, the tangent the Duff et al. 2017 basis of the normal (as Mitsuba's
//! `coordinate_system`), the uv zero.
//!
//! Outside the grid `f` continues as the value at the nearest grid point plus the distance to
//! it, which keeps it continuous and, with the grid's own bound, Lipschitz. Segment bounds are
//! Lipschitz lines with the largest gradient bound of the cells the segment crosses: in a cell
//! the derivative of the interpolant along an axis is a bilinear blend of the cell's four edge
//! differences along that axis, so it is bounded by the largest of them.

use super::{Aabb, MeanSurface, SegmentBound, SegmentEnd, SurfacePoint};
use crate::error::{Error, ErrorKind, Result};
use glam::{DMat3, DVec2, DVec3, IVec3};

/// A similarity transform's columns may differ in length by this relative amount.
const SIMILARITY_TOLERANCE: f64 = 1e-6;
/// The largest slope of the interpolant accepted, in world units per world unit. A signed
/// distance's trilinear interpolant has at most √3; values in voxel units instead of object
/// units give about the resolution; beyond 1e6 a value is a sentinel ("far", 1e30, FLT_MAX),
/// whose cells would cut every step near them to 1e-30 of the way (found by fuzzing: one sample
/// of 1e30 made each tracking call run 65,536 segments and fail).
const MAX_SLOPE: f64 = 1e6;
/// Cells per axis of a block of [`GridSurface::block_lipschitz`].
const BLOCK: i32 = 8;
/// A segment's bound reads at most this many cells (or blocks) of the gradient bounds: beyond,
/// blocks of [`BLOCK`]³ cells, then the global bound (a segment across a 512³ grid would
/// otherwise read 1.3e8 cells per bound).
const MAX_BOX_READS: i32 = 4096;

#[derive(Clone, Debug)]
pub struct GridSurface {
    /// Samples per axis (each at least 2).
    dims: IVec3,
    /// `x` fastest, then `y`, then `z` (the order of Mitsuba's `.vol` files).
    values: Vec<f32>,
    /// World = `rotation * scale * object + translation`.
    rotation: DMat3,
    scale: f64,
    translation: DVec3,
    /// Per cell, a bound of `|∇f|` (world units per world unit; rounded up to f32).
    lipschitz: Vec<f32>,
    /// Per block of [`BLOCK`]³ cells, the largest of its cells' bounds.
    block_lipschitz: Vec<f32>,
    /// A Lipschitz constant of `f` everywhere (the largest cell's, plus 1 beyond the grid).
    global_lipschitz: f64,
    bounds: Aabb,
}

impl GridSurface {
    /// `values` at `dims` corners (`x` fastest) of the unit cube of object space;
    /// `to_world` = (3×3 linear part, translation), a rotation times a uniform scale.
    pub fn new(values: &[f32], dims: [usize; 3], linear: DMat3, translation: DVec3) -> Result<GridSurface> {
        let invalid = |m: String| Error::new(ErrorKind::InvalidArgument, m);
        if dims.iter().any(|n| !(2..=1 << 20).contains(n)) {
            return Err(invalid(format!("grid dimensions must lie in [2, 2^20] per axis, got {dims:?}")));
        }
        let count = dims[0].checked_mul(dims[1]).and_then(|n| n.checked_mul(dims[2])).ok_or_else(|| invalid(format!("grid dimensions {dims:?} are too large")))?;
        if values.len() != count {
            return Err(invalid(format!("the grid has {} values for dimensions {dims:?} ({count} expected)", values.len())));
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(invalid(format!("grid value {i} is not finite: {}", values[i])));
        }
        if !(linear.is_finite() && translation.is_finite()) {
            return Err(invalid(format!("to_world must be finite, got {linear} + {translation}")));
        }
        let lengths = [linear.x_axis.length(), linear.y_axis.length(), linear.z_axis.length()];
        let scale = (lengths[0] * lengths[1] * lengths[2]).cbrt();
        let orthogonal = [(linear.x_axis, linear.y_axis), (linear.y_axis, linear.z_axis), (linear.x_axis, linear.z_axis)].iter().all(|(a, b)| a.dot(*b).abs() <= SIMILARITY_TOLERANCE * scale * scale);
        if !(scale > 0.0) || lengths.iter().any(|l| (l - scale).abs() > SIMILARITY_TOLERANCE * scale) || !orthogonal || linear.determinant() <= 0.0 {
            return Err(invalid(format!("to_world must be a rotation times a uniform scale (distances must stay distances), got {linear}")));
        }
        let rotation = linear * (1.0 / scale);
        let dims = IVec3::new(dims[0] as i32, dims[1] as i32, dims[2] as i32);
        let index = |x: i32, y: i32, z: i32| ((z * dims.y + y) * dims.x + x) as usize;
        // The surface must be enclosed by the grid: its outer faces lie outside (f > 0).
        for z in 0..dims.z {
            for y in 0..dims.y {
                for x in 0..dims.x {
                    let on_face = x == 0 || y == 0 || z == 0 || x == dims.x - 1 || y == dims.y - 1 || z == dims.z - 1;
                    if on_face && !(values[index(x, y, z)] > 0.0) {
                        return Err(invalid(format!("grid value at ({x}, {y}, {z}) on the grid's boundary is {} <= 0: the surface must lie inside the grid", values[index(x, y, z)])));
                    }
                }
            }
        }
        let cells = (dims - IVec3::ONE).max(IVec3::ONE);
        let mut lipschitz = Vec::with_capacity((cells.x * cells.y * cells.z) as usize);
        for z in 0..cells.z {
            for y in 0..cells.y {
                for x in 0..cells.x {
                    let v = |dx: i32, dy: i32, dz: i32| f64::from(values[index(x + dx, y + dy, z + dz)]);
                    let mut squared = 0.0;
                    for axis in 0..3 {
                        let mut largest: f64 = 0.0;
                        for a in 0..2 {
                            for b in 0..2 {
                                let (lo, hi) = match axis {
                                    0 => (v(0, a, b), v(1, a, b)),
                                    1 => (v(a, 0, b), v(a, 1, b)),
                                    _ => (v(a, b, 0), v(a, b, 1)),
                                };
                                largest = largest.max((hi - lo).abs());
                            }
                        }
                        // Object units per object unit: one cell spans 1/(n − 1).
                        let per_unit = largest * f64::from(dims[axis] - 1);
                        squared += per_unit * per_unit;
                    }
                    // World distances scale like object ones: the gradient is scale-free.
                    lipschitz.push(round_up(squared.sqrt() * (1.0 + 1e-9)));
                }
            }
        }
        let corners = (0..8).map(|i| linear * DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64) + translation);
        let (min, max) = corners.fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), c| (lo.min(c), hi.max(c)));
        if let Some(i) = lipschitz.iter().position(|&l| f64::from(l) > MAX_SLOPE) {
            let i = i as i32;
            let cell = (i % cells.x, (i / cells.x) % cells.y, i / (cells.x * cells.y));
            return Err(invalid(format!(
                "grid values change by up to {:e} per unit of distance in cell {cell:?}, more than {MAX_SLOPE:e}: the samples must be signed distances in object units (which change by at most sqrt(3) in a cell); clamp sentinel values such as 1e30 to the grid's diagonal",
                lipschitz[i as usize]
            )));
        }
        let global_lipschitz = f64::from(lipschitz.iter().copied().fold(0.0f32, f32::max)) + 1.0;
        let blocks = block_dims(cells);
        let mut block_lipschitz = vec![0.0f32; (blocks.x * blocks.y * blocks.z) as usize];
        for z in 0..cells.z {
            for y in 0..cells.y {
                for x in 0..cells.x {
                    let b = &mut block_lipschitz[(((z / BLOCK) * blocks.y + y / BLOCK) * blocks.x + x / BLOCK) as usize];
                    *b = b.max(lipschitz[((z * cells.y + y) * cells.x + x) as usize]);
                }
            }
        }
        Ok(GridSurface { dims, values: values.to_vec(), rotation, scale, translation, lipschitz, block_lipschitz, global_lipschitz, bounds: Aabb { min, max } })
    }

    /// Grid coordinates (`[0, n − 1]` per axis inside) of a world point.
    fn to_grid(&self, p: DVec3) -> DVec3 {
        let object = self.rotation.transpose() * (p - self.translation) / self.scale;
        object * (self.dims - IVec3::ONE).as_dvec3()
    }

    fn value(&self, x: i32, y: i32, z: i32) -> f64 {
        f64::from(self.values[((z * self.dims.y + y) * self.dims.x + x) as usize])
    }

    /// The interpolated value (object units) and its gradient in grid coordinates at `g`
    /// (clamped into the grid).
    fn trilinear(&self, g: DVec3) -> (f64, DVec3) {
        let top = (self.dims - IVec3::ONE).as_dvec3();
        let g = g.clamp(DVec3::ZERO, top);
        let cell = g.floor().as_ivec3().min(self.dims - IVec3::splat(2)).max(IVec3::ZERO);
        let t = g - cell.as_dvec3();
        let c = |dx: i32, dy: i32, dz: i32| self.value(cell.x + dx, cell.y + dy, cell.z + dz);
        let lerp = |a: f64, b: f64, s: f64| a + s * (b - a);
        // Along x on the four y/z edges, then y, then z.
        let (c00, c10, c01, c11) = (lerp(c(0, 0, 0), c(1, 0, 0), t.x), lerp(c(0, 1, 0), c(1, 1, 0), t.x), lerp(c(0, 0, 1), c(1, 0, 1), t.x), lerp(c(0, 1, 1), c(1, 1, 1), t.x));
        let (c0, c1) = (lerp(c00, c10, t.y), lerp(c01, c11, t.y));
        let value = lerp(c0, c1, t.z);
        let dx = {
            let e = |dy: i32, dz: i32| c(1, dy, dz) - c(0, dy, dz);
            lerp(lerp(e(0, 0), e(1, 0), t.y), lerp(e(0, 1), e(1, 1), t.y), t.z)
        };
        let dy = lerp(c10 - c00, c11 - c01, t.z);
        let dz = c1 - c0;
        (value, DVec3::new(dx, dy, dz))
    }

    /// The largest gradient bound of the cells that the segment `p + s d`, `s ∈ [0, length]`,
    /// can touch (the cells of its grid-space bounding box, one cell of margin for rounding).
    fn lipschitz_along(&self, p: DVec3, d: DVec3, length: f64) -> f64 {
        let (a, b) = (self.to_grid(p), self.to_grid(p + length * d));
        let cells = self.dims - IVec3::ONE;
        // Clamped before the conversion to integers: a segment 1e50 long reaches grid
        // coordinates beyond i32 (found by fuzzing: the saturated i32::MIN − 1 overflowed; wrapped,
        // it would have bounded no cell). A non-finite end takes every cell.
        let last = (cells - IVec3::ONE).as_dvec3();
        let (lo, hi) = if a.is_finite() && b.is_finite() {
            ((a.min(b).floor() - 1.0).clamp(DVec3::ZERO, last).as_ivec3(), (a.max(b).floor() + 1.0).clamp(DVec3::ZERO, last).as_ivec3())
        } else {
            (IVec3::ZERO, last.as_ivec3())
        };
        let top = (self.dims - IVec3::ONE).as_dvec3();
        let inside = |g: DVec3| g.cmpge(DVec3::ZERO).all() && g.cmple(top).all();
        let reads = |lo: IVec3, hi: IVec3| (hi - lo + IVec3::ONE).as_dvec3().element_product();
        let largest = if reads(lo, hi) <= f64::from(MAX_BOX_READS) {
            box_max(&self.lipschitz, cells, lo, hi)
        } else if reads(lo / BLOCK, hi / BLOCK) <= f64::from(MAX_BOX_READS) {
            box_max(&self.block_lipschitz, block_dims(cells), lo / BLOCK, hi / BLOCK)
        } else {
            return self.global_lipschitz;
        };
        // Beyond the grid f adds the distance to the grid (slope 1) to a value that moves with
        // the nearest grid point (slope at most the grid's): both ends inside keep the segment
        // inside the (convex) box.
        if inside(a) && inside(b) {
            f64::from(largest)
        } else {
            f64::from(largest) + 1.0
        }
    }
}

/// Blocks of [`BLOCK`]³ per axis covering `cells`.
fn block_dims(cells: IVec3) -> IVec3 {
    (cells + IVec3::splat(BLOCK - 1)) / BLOCK
}

/// The largest of `values` (`x` fastest over `dims`) in the box `[lo, hi]`.
fn box_max(values: &[f32], dims: IVec3, lo: IVec3, hi: IVec3) -> f32 {
    let mut largest: f32 = 0.0;
    for z in lo.z..=hi.z {
        for y in lo.y..=hi.y {
            for x in lo.x..=hi.x {
                largest = largest.max(values[((z * dims.y + y) * dims.x + x) as usize]);
            }
        }
    }
    largest
}

/// The smallest f32 at least `x`.
fn round_up(x: f64) -> f32 {
    let y = x as f32;
    if f64::from(y) < x {
        f32::from_bits(y.to_bits() + 1)
    } else {
        y
    }
}

impl MeanSurface for GridSurface {
    type Cache = ();

    fn point(&self, p: DVec3) -> Result<SurfacePoint> {
        let g = self.to_grid(p);
        let top = (self.dims - IVec3::ONE).as_dvec3();
        let inside = g.clamp(DVec3::ZERO, top);
        let (value, gradient) = self.trilinear(g);
        // Grid units → object units (a cell spans 1/(n − 1)) → world (rotation; scale cancels).
        let world_gradient = self.rotation * (gradient * top);
        let outside = (g - inside) / top * self.scale;
        let (f, normal) = if outside == DVec3::ZERO {
            (value * self.scale, world_gradient.try_normalize().unwrap_or(self.rotation.z_axis))
        } else {
            // Beyond the grid: the value at the nearest grid point plus the distance to it.
            let away = self.rotation * outside;
            (value * self.scale + away.length(), away.normalize())
        };
        let tangent = normal.any_orthonormal_pair().0;
        Ok(SurfacePoint { f, normal, tangent, uv: DVec2::ZERO })
    }

    fn bound(&self, start: &SurfacePoint, p: DVec3, d: DVec3, length: f64, _tolerance: f64, _: &mut ()) -> Result<SegmentBound> {
        let lipschitz = self.lipschitz_along(p, d, length);
        Ok(SegmentBound { length, f_lo: [start.f, start.f - lipschitz * length], f_hi: [start.f, start.f + lipschitz * length], cos: [-1.0, 1.0], end: SegmentEnd::Unknown })
    }

    /// Steps by the gradient bound of the cells near the ray, not the grid's largest (one wild
    /// sample made every step of every ray 1e30 times too short, found by fuzzing). The cells
    /// a step of `gap / L_near` reaches bound `f` on it; when they allow a larger slope `L`,
    /// `gap / L` is shorter, so its cells are among them and `f` stays above `level`.
    fn clearance(&self, start: &SurfacePoint, p: DVec3, d: DVec3, level: f64, _: &mut ()) -> f64 {
        let gap = start.f - level;
        if !(gap > 0.0) {
            return 0.0;
        }
        let near = self.lipschitz_along(p, d, 0.0);
        let reach = self.lipschitz_along(p, d, gap / near);
        gap / near.max(reach)
    }

    /// An interpolated distance may change faster than the distance itself.
    fn lipschitz(&self) -> f64 {
        self.global_lipschitz
    }

    fn bounding_box(&self) -> Aabb {
        self.bounds
    }
}
