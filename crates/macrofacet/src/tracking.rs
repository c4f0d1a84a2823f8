//! Tracking through a macrofacet medium around a curved mean surface: free flights (delta
//! tracking) and transmittance (residual ratio tracking), with majorants built from the planar
//! closed forms.
//!
//! The medium's extinction at `p` for propagation direction `d` is
//! `σ_t = ρ(f(p)) σ(d_local)` (seeds/000 Eq. 13, 14/31), with `f` and the local frame from the
//! [`MeanSurface`]. On a segment where the surface guarantees `f >= f_lo(s)` (linear) and
//! `d·n ∈ [c_lo, c_hi]` ([`SegmentBound`]), the majorant
//!
//! `μ(s) = S_up ρ(f_lo(s))`,  `S_up >= σ(d_local)` for every frame with `d·n` in that range,
//!
//! bounds `σ_t` (ρ decreases with `f`), and its optical depth and inverse are the closed forms of
//! a planar shell ([`HeightProfile::density_integral`]). For a planar surface the majorant *is*
//! `σ_t`: every tentative collision is real. On a thin shell around a curved surface it is tight
//! to the shell's curvature, so a free flight costs about two surface queries. Tentative
//! collisions are accepted with probability `σ_t / μ` (delta tracking, Woodcock et al. 1965), so
//! the estimate is unbiased whatever the curvature, as long as the surface's bounds hold; each
//! tentative collision checks `σ_t <= μ` and counts violations in [`TrackStats`].
//!
//! Transmittance uses a control `μ_c(s) = S_lo ρ(f_hi(s)) <= σ_t` with analytic optical depth and
//! ratio tracking of the residual (Novák et al. 2014): `T = exp(−∫μ_c) Π (1 − (σ_t − μ_c)/(μ − μ_c))`
//! over tentative collisions of the residual majorant `μ − μ_c`, obtained by thinning those of
//! `μ`. A thin shell's shadow ray mostly needs no surface query beyond the segment bounds.
//!
//! Directions: `d` is the propagation direction (unit). Random numbers come from a [`Pcg32`] the
//! caller seeds per call.

use crate::error::{Error, ErrorKind, Result};
use crate::field::{Constant, LocalParams, MediumField, ParamBounds};
use crate::frame::Frame;
use crate::height::HeightProfile;
use crate::medium::MacrofacetMedium;
use crate::ndf::{MicrofacetDistribution, Ndf, Side};
use crate::opaque_core::{descent_transmittance_bound, opaque_core, OpaqueCore};
use crate::ordered::{largest_magnitude, less, more};
use crate::rng::Pcg32;
use crate::surface::{MeanSurface, SegmentBound, SegmentEnd, SurfacePoint};
use glam::DVec3;
use std::ops::ControlFlow;

/// The PCG32 stream ("mftrack") of the C ABI's tracking calls: `mf_track_*` with `seed` equals
/// [`Tracker::with_bounds`] (with [`ProjectedAreaBounds::of`] the medium, built with its handle)
/// with `Pcg32::new(seed, TRACK_STREAM)`.
pub const TRACK_STREAM: u64 = 0x006d_6674_7261_636b;

/// Counts of one tracking call, for tests and benchmarks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TrackStats {
    /// Calls of [`MeanSurface::point`] / [`MeanSurface::point_on_segment`].
    pub surface_queries: u32,
    /// Calls of [`MeanSurface::bound`] (tracked segments).
    pub segments: u32,
    /// Tentative collisions at which `σ_t` was evaluated.
    pub tentative_collisions: u32,
    /// Tentative collisions where `σ_t > μ` (or `σ_t < μ_c`): the surface's bounds were wrong
    /// there. Zero for a correct surface.
    pub majorant_violations: u32,
}

impl TrackStats {
    pub fn add(&mut self, other: &TrackStats) {
        self.surface_queries += other.surface_queries;
        self.segments += other.segments;
        self.tentative_collisions += other.tentative_collisions;
        self.majorant_violations += other.majorant_violations;
    }
}

/// The outcome of a tracked free flight.
// (A collision is larger than a pass; boxing it would allocate per collision.)
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TrackedFlight {
    /// A real collision at distance `t`, where the surface is `point` (its frame is the local
    /// frame of the phase function there; its normal unit; its uv completed unless the tracker
    /// was built [`Tracker::without_uv`]). `hint` names where the surface found it, for the calls
    /// that start there ([`Tracker::from_hint`]; 0 for none).
    Scatter { t: f64, point: SurfacePoint, local: LocalParams, hint: u64 },
    /// No collision in `[0, t_max]`.
    Pass,
}

/// Segments tracked per call before giving up with an error (not counting the segments that
/// start at a tentative collision, which [`MAX_TENTATIVE`] bounds). Empty segments double in
/// length, so even an unbounded surface with `t_max = +∞` ends long before this. Built for
/// fuzzing (`cfg(fuzzing)`, set by cargo-fuzz), this cap and the next are 16 times lower: calls that
/// reach them took ~0.1–1 s each and held the fuzzers to ~100 executions/s; the paths are the
/// same, and no call of the regression tests comes near either cap.
const MAX_SEGMENTS: u32 = if cfg!(fuzzing) { 1 << 12 } else { 1 << 16 };
/// Tentative collisions one call may take. Ordinary shells need a handful per segment; a
/// majorant that is loose by many orders of magnitude (σ = 1e-50 deep inside a sphere of radius
/// 1000, found by fuzzing) would otherwise run without end: such a call fails with a message.
const MAX_TENTATIVE: u64 = if cfg!(fuzzing) { 1 << 13 } else { 1 << 17 };
/// A segment whose bounds of `f` differ by more than this many σ at its end is halved (up to
/// [`MAX_SHORTENINGS`] times): loose bounds cost tentative collisions, short segments cost
/// surface queries. Against 1σ, 4σ rendered with 4.9 % fewer instructions the fuzzy sphere of
/// bench/gpis_compare.xml, 2.6 % fewer the torus anchor, 1.0 % and 5.1 % fewer the default
/// scene's in-between and volume-like tori (2σ: 3.9, 1.5, 1.6 and 4.4 %). Free flights sample
/// the same distribution whatever it is, and ratio tracking's variance only falls with a looser
/// majorant.
const LOOSENESS_SIGMAS: f64 = 4.0;
const MAX_SHORTENINGS: u32 = 4;
/// A halving that leaves more than this fraction of the looseness did not pay (padding for the
/// rounding of coordinates does not shrink with the segment): the longer segment is kept.
const SHORTENING_GAIN: f64 = 0.75;
/// A field's `σ` range may halve a segment this many times, until its majorant factor
/// `(σ_hi/σ_lo)²` is at most [`MAX_DENSITY_FACTOR`] or stops falling.
const MAX_FIELD_SHORTENINGS: u32 = 6;
const MAX_DENSITY_FACTOR: f64 = 1.5;
/// A segment whose frame normals span more than this range of `d·n`, whose `S_up` exceeds
/// [`LOOSE_AREA`] times the projected area at its start and which expects more than
/// [`WIDE_RANGE_COLLISIONS`] tentative collisions is shortened to about that many (at most
/// [`MAX_WIDE_SHORTENINGS`] times per segment).
const WIDE_COS_RANGE: f64 = 0.5;
const LOOSE_AREA: f64 = 4.0;
const WIDE_RANGE_COLLISIONS: f64 = 8.0;
const MAX_WIDE_SHORTENINGS: u32 = 2;
/// Ulps of `|q|∞ + t` by which the bounds of `f` are widened: the rounding of the points
/// `q = origin + t d` where the surface is queried (of `t d` and of the sum) times the slope of
/// `f` (1 for a signed distance, a little more for an interpolated grid).
const POSITION_ROUNDING: f64 = 4.0 * f64::EPSILON;
/// Lipschitz steps above the shell per segment (each one surface query).
const MAX_SKIPS: u32 = 64;
/// Default reach of a segment, in σ of change of `f` (covers the shell from its top to deep
/// below the mean surface, where a collision is nearly certain: from the top face of a `k = 3`
/// shell down to `f = −3σ` a normally incident ray passes with probability `Φ(−3)/Φ(3)`, 1e-3,
/// against 0.16 at 4σ, which made one flight in five bound a second segment). Against 4σ,
/// 6σ rendered with 5.5 % fewer instructions the thin sphere anchor, 1.9 % the torus anchor,
/// 1.6 % the fuzzy sphere of bench/gpis_compare.xml and 0.5 % the default scene (5σ: 4.1, 1.8
/// and 1.6 %; 7σ: 5.7, 1.5 and 1.7 %).
const SEGMENT_SIGMAS: f64 = 6.0;
/// Above `top + SKIP_SIGMAS σ` the tracker steps by the Lipschitz bound instead of bounding a
/// segment: cheaper for surfaces whose bounds cost more than a point query. Against 2σ, 0.5σ
/// rendered the torus anchor with 3.6 % fewer instructions and the default scene with 2.9 %
/// fewer (1σ: 2.6 % on the torus, 0.25σ: 3.8 %; at 0 the steps of `f − top` toward the top
/// face shrink geometrically on grazing rays, +49 %). Surfaces with exact clearances skip to
/// the top face itself.
const SKIP_SIGMAS: f64 = 0.5;
/// Ratio tracking: below this estimate, continue by Russian roulette (unbiased; ends walks into
/// the opaque interior). Against 0.1, 0.5 rendered the default scene (160×90, 2 spp) with 6.6 %
/// fewer instructions, the thin torus anchor 1.9 % and the fuzzy sphere of
/// bench/gpis_compare.xml 2.6 % fewer (0.3: 4.2 % on the default scene; 1, a binary estimate:
/// 11 %, 3.5 % and 3.6 %, but no fractional estimate is left). The images' noise did not rise
/// measurably: the mean squared difference of two seeds' renders of the default scene (240×135,
/// 32 spp) was 0.005221 against 0.005232 (1: 0.005256), of the fuzzy sphere (96², 64 spp)
/// 0.000633 at 0.1, 0.3 and 0.5 (1: 0.000635). Shadow rays in these scenes mostly pass the
/// shell or end in an opaque interior; the path's other sampling dominates the noise.
pub const ROULETTE_THRESHOLD: f64 = 0.5;
/// Relative slack of the majorant check (rounding of `f` and of the projected area).
const VIOLATION_SLACK: f64 = 1e-9;

/// Upper and lower bounds of `σ(d_local)` over frames with a given range of `d·n`: what a
/// tracker derives from its medium's distribution before any segment (two envelope
/// distributions and a Lipschitz constant, a few hundred instructions and a kilobyte, built per
/// call by [`Tracker::new`]). A host that tracks many rays through one medium builds them once
/// ([`Self::of`], [`Tracker::with_bounds`]): they then also hold both bounds over [`AREA_CELLS`]
/// cells of `d·n`, which answer the ranges of most segments without evaluating a projected
/// area.
#[derive(Clone, Debug)]
pub struct ProjectedAreaBounds {
    upper: Ndf,
    lower: Ndf,
    lipschitz: f64,
    /// The distribution they bound.
    source: Ndf,
    /// Whether `source` is isotropic (the tracker's per-call question, answered once).
    isotropic: bool,
    /// Cell `k` holds the bounds over `d·n ∈ [−1 + k h − η, −1 + (k + 1) h + η]`, `h = 2 /`
    /// [`AREA_CELLS`], `η` = [`CELL_OVERLAP`] (none for per-call bounds): level 0 of a sparse
    /// table whose level `j` holds, at `k`, the extremes of cells `k..k + 2^j` (where they exist),
    /// so that any range of cells is the union of two entries of one level.
    cells: Option<Box<[[AreaCell; AREA_CELLS]]>>,
    /// [`Self::descent_rate`] for frames that are not, and that are, the gradient's (built with
    /// the cells, from them: a host asks per shadow ray).
    descent_rates: Option<[f64; 2]>,
}

/// Cells of `d·n ∈ [−1, 1]` in [`ProjectedAreaBounds::of`] (8 bytes each, in each of the
/// 11 levels of their sparse table).
pub const AREA_CELLS: usize = 1024;
/// Levels of the cells' sparse table: spans of `1, 2, 4, …, AREA_CELLS` cells. Any range then
/// costs two loads: a thin shell's segment across the unit sphere spans up to ~10 cells, the
/// fuzzy sphere's of bench/gpis_compare.xml (σ = 0.02) ~100, which a scan of at most 32 cells
/// left to the exact bound (two evaluations of the projected area, ~4 % of its rendering).
const CELL_LEVELS: usize = AREA_CELLS.trailing_zeros() as usize + 1;
/// How far each cell reaches into its neighbours: covers the rounding of a cosine's cell index
/// (a few ulps of `(c + 1) AREA_CELLS / 2`, 1e-16 in `c`).
const CELL_OVERLAP: f64 = 1e-12;
/// A cell's `S_up` answers only where it is within this factor of the exact one over any part
/// of it (its bound over the inner bound of the same envelope): a looser majorant costs
/// tentative collisions (each ~0.8k instructions) against the ~0.3k of an exact bound.
/// Elsewhere (a narrow lobe's grazing tail, anisotropic envelopes) the exact bound. Against
/// 1.1, 2 rendered the thin sphere anchor with 0.65 % fewer instructions, the torus anchor
/// 0.5 % and the default scene (160×90, 2 spp) 1.0 % (4: 0.76, 0.6 and 1.05 %): the exact
/// bound answered 10,462 of the thin sphere anchor's 42,243 area bounds, now 5,273.
const CELL_LOOSENESS_UPPER: f64 = 2.0;
/// The same for a cell's `S_lo`, the control of transmittance estimates. A looser control would
/// leave more to ratio tracking's roulette, that is more noise (not measured), for 0.1–0.4 %
/// fewer instructions at 2 or 4 on the same scenes; it stays tight.
const CELL_LOOSENESS_LOWER: f64 = 1.1;

/// The bounds of one cell of `d·n` ([`ProjectedAreaBounds`]): `S_up` over the cell where it is
/// within [`CELL_LOOSENESS_UPPER`] of the upper envelope's smallest area there, else `+∞`; `S_lo`
/// where the lower envelope's largest area is within [`CELL_LOOSENESS_LOWER`] of it, else `−∞` (so that the
/// largest and smallest over a range of cells say at once whether every cell answers). In f32,
/// rounded outward (`S_up` up, `S_lo` down), which halves the table (88 KiB) for a looseness of
/// at most 2^-24 relative.
#[derive(Clone, Copy, Debug)]
struct AreaCell {
    upper: f32,
    lower: f32,
}

impl AreaCell {
    /// The cell of the f64 bounds `upper` (its floor `upper_floor`) and `lower` (its ceiling
    /// `lower_ceiling`), each rounded outward to f32 and kept where still within
    /// [`CELL_LOOSENESS_UPPER`] of the floor ([`CELL_LOOSENESS_LOWER`] of the ceiling): not beyond f32's range, nor deep among its
    /// subnormals.
    fn new(upper: f64, upper_floor: f64, lower: f64, lower_ceiling: f64) -> AreaCell {
        let (up, down) = (f32_at_least(upper), -f32_at_least(-lower));
        AreaCell {
            upper: if f64::from(up) <= CELL_LOOSENESS_UPPER * upper_floor { up } else { f32::INFINITY },
            lower: if lower_ceiling <= CELL_LOOSENESS_LOWER * f64::from(down) { down } else { f32::NEG_INFINITY },
        }
    }
}

/// The smallest f32 `>= x` (NaN stays NaN). By hand: `f32::next_up` needs Rust 1.86, the crate
/// supports 1.80.
fn f32_at_least(x: f64) -> f32 {
    let nearest = x as f32;
    if !(f64::from(nearest) < x) {
        return nearest;
    }
    // The next f32 up from a finite or −∞ `nearest` below x (bits count away from zero).
    if nearest == 0.0 {
        f32::from_bits(1)
    } else if nearest > 0.0 {
        f32::from_bits(nearest.to_bits() + 1)
    } else {
        f32::from_bits(nearest.to_bits() - 1)
    }
}

impl ProjectedAreaBounds {
    /// The bounds of a medium's distribution, with their cells: 4 × [`AREA_CELLS`] area bounds at
    /// build (each cell's two bounds and the two extremes that say whether it answers) and 88 KiB
    /// with the sparse table: for hosts that build them once per medium.
    pub fn of(medium: &MacrofacetMedium) -> Self {
        Self::with_cells(&medium.phase.ndf)
    }

    fn with_cells(ndf: &Ndf) -> Self {
        let mut bounds = Self::new(ndf);
        let h = 2.0 / AREA_CELLS as f64;
        let mut table = vec![[AreaCell { upper: f32::INFINITY, lower: f32::NEG_INFINITY }; AREA_CELLS]; CELL_LEVELS].into_boxed_slice();
        for (k, slot) in table[0].iter_mut().enumerate() {
            let cell = [-1.0 + k as f64 * h - CELL_OVERLAP, -1.0 + (k + 1) as f64 * h + CELL_OVERLAP];
            let upper_floor = bounds.bound(&bounds.upper, cell, Side::Lower) * (1.0 - AREA_ROUNDING);
            let lower_ceiling = bounds.bound(&bounds.lower, cell, Side::Upper) * (1.0 + AREA_ROUNDING);
            // (Both zero in a lobe's far tail: tight.)
            *slot = AreaCell::new(bounds.upper_exact(cell), upper_floor, bounds.lower_exact(cell), lower_ceiling);
        }
        for j in 1..CELL_LEVELS {
            let half = 1 << (j - 1);
            for k in 0..AREA_CELLS {
                // Past the last cell the entry is never read (a range ends at the last cell).
                let (a, b) = (table[j - 1][k], table[j - 1][(k + half).min(AREA_CELLS - 1)]);
                table[j][k] = AreaCell { upper: a.upper.max(b.upper), lower: a.lower.min(b.lower) };
            }
        }
        bounds.cells = Some(table);
        bounds.descent_rates = Some([false, true].map(|gradient| bounds.descent_rate(gradient)));
        bounds
    }

    /// Without cells: for bounds built per call or per segment.
    fn new(ndf: &Ndf) -> Self {
        let (upper, lower) = ndf.isotropic_envelope();
        ProjectedAreaBounds { upper, lower, lipschitz: upper.projected_area_lipschitz(), source: *ndf, isotropic: ndf.is_isotropic(), cells: None, descent_rates: None }
    }

    /// The opaque core's `κ` before the division by the surface's Lipschitz constant
    /// ([`crate::opaque_core`]): a lower bound of `σ(d)/|d·n|` over descending directions where
    /// the frame normal is the gradient's direction (`gradient`), else of `σ(d)` over every
    /// direction. From the area's lower bounds over [`CORE_PIECES`] pieces of `d·n` (one bound
    /// over a wide range pairs its ends' extremes: for Beckmann the grazing `w_z` with the spread
    /// of normal incidence, 0). Where the frame is the gradient, over `|d·n| ∈ [q^(k+1), q^k]`
    /// (the last piece down to 0) divided by the piece's largest `|d·n|`: geometric pieces keep
    /// that quotient within `q` of `σ/|d·n|` for smooth lobes, whose `σ` tends to `|d·n|`.
    /// Otherwise over even pieces of `[−1, 1]`.
    fn descent_rate(&self, gradient: bool) -> f64 {
        if let Some(rates) = self.descent_rates {
            return rates[usize::from(gradient)];
        }
        if gradient {
            (0..CORE_PIECES)
                .map(|k| {
                    let (large, small) = (CORE_RATIO.powi(k as i32), if k + 1 == CORE_PIECES { 0.0 } else { CORE_RATIO.powi(k as i32 + 1) });
                    self.lower([-large, -small]) / large
                })
                .fold(f64::INFINITY, f64::min)
        } else {
            let step = 2.0 / CORE_PIECES as f64;
            (0..CORE_PIECES).map(|k| self.lower([-1.0 + k as f64 * step, -1.0 + (k + 1) as f64 * step])).fold(f64::INFINITY, f64::min)
        }
    }

    /// The cells' bound of `side` over `cos` when every cell it meets is tight. A range within
    /// cells `k0..=k1` lies within their union, so the largest (smallest) of their bounds holds
    /// over it; and it is within its side's looseness ([`CELL_LOOSENESS_UPPER`],
    /// [`CELL_LOOSENESS_LOWER`]) of the exact bound, which is at least (at
    /// most) each cell's smallest (largest) area, as the range meets every cell. The extremes
    /// over `k0..=k1` are those of the two table entries of span `2^j <= k1 − k0 + 1` that start
    /// at `k0` and end at `k1`.
    fn tabulated(&self, cos: [f64; 2], side: Side) -> Option<f64> {
        let cells = self.cells.as_deref()?;
        if !(cos[0] >= -1.0 && cos[1] <= 1.0) {
            return None;
        }
        let index = |c: f64| (((c + 1.0) * (0.5 * AREA_CELLS as f64)) as usize).min(AREA_CELLS - 1);
        let (k0, k1) = (index(cos[0]), index(cos[1]));
        // (An unordered range, which validated bounds never give, takes the exact bound too.)
        if k1 < k0 {
            return None;
        }
        let j = (k1 - k0 + 1).ilog2() as usize;
        let (a, b) = (&cells[j][k0], &cells[j][k1 + 1 - (1 << j)]);
        let bound = match side {
            Side::Upper => a.upper.max(b.upper),
            Side::Lower => a.lower.min(b.lower),
        };
        bound.is_finite().then_some(f64::from(bound))
    }

    /// `S_up >= σ(d_local)` for every frame whose normal has `d·n ∈ [c_lo, c_hi]`, any tangent:
    /// from the cells where they answer, else [`Self::upper_exact`].
    fn upper(&self, cos: [f64; 2]) -> f64 {
        self.tabulated(cos, Side::Upper).unwrap_or_else(|| self.upper_exact(cos))
    }

    /// `S_up` from the distribution.
    /// `σ(d) = projected_area(−d_local)` sees `w_z = −d·n`. Where a closed form is monotone
    /// ([`Ndf::projected_area_bound`]: isotropic gpss, Beckmann, GGX up to α = 1) the range's
    /// extremes give it exactly; otherwise, over the angle interval, an L-Lipschitz function
    /// exceeds neither the larger end value by more than `L × width / 2` nor the midpoint value
    /// by more than that (one evaluation for narrow ranges).
    fn upper_exact(&self, cos: [f64; 2]) -> f64 {
        self.bound(&self.upper, cos, Side::Upper) * (1.0 + AREA_ROUNDING)
    }

    /// `S_lo <= σ(d_local)` over the same frames (at least 0): from the cells where they answer.
    fn lower(&self, cos: [f64; 2]) -> f64 {
        self.tabulated(cos, Side::Lower).unwrap_or_else(|| self.lower_exact(cos))
    }

    /// `S_lo` from the distribution.
    fn lower_exact(&self, cos: [f64; 2]) -> f64 {
        (self.bound(&self.lower, cos, Side::Lower) * (1.0 - AREA_ROUNDING)).max(0.0)
    }

    fn bound(&self, ndf: &Ndf, cos: [f64; 2], side: Side) -> f64 {
        // Closed forms monotone over w_z = −d·n (and the spread): exact at the range's extremes,
        // the range widened by σ_t's rounding of d·n (COS_ROUNDING).
        let w_z = [(-cos[1] - COS_ROUNDING).max(-1.0), (-cos[0] + COS_ROUNDING).min(1.0)];
        if let Some(bound) = ndf.projected_area_bound(w_z, side) {
            return bound;
        }
        let sign = side.sign();
        let area = |theta: f64| {
            let (sin, cos) = theta.sin_cos();
            ndf.projected_area(DVec3::new(sin, 0.0, -cos))
        };
        let extreme = |a: f64, b: f64| if side == Side::Upper { a.max(b) } else { a.min(b) };
        let (theta_lo, theta_hi) = (cos[1].clamp(-1.0, 1.0).acos(), cos[0].clamp(-1.0, 1.0).acos());
        let width = theta_hi - theta_lo;
        let inside = if width < NARROW_RANGE {
            area(0.5 * (theta_lo + theta_hi)) + sign * 0.5 * self.lipschitz * width
        } else {
            extreme(area(theta_lo), area(theta_hi)) + sign * 0.5 * self.lipschitz * width
        };
        // σ_t rounds d·n up to COS_ROUNDING past the range. Usually the area changes over that
        // sliver by less than half the relative margin AREA_ROUNDING (the Lipschitz bound times
        // the sliver's angle); otherwise the area is monotone over the sliver, so its far end
        // bounds it.
        let sliver = sliver_angle(cos[0]).max(sliver_angle(cos[1]));
        if self.lipschitz * sliver <= 0.5 * AREA_ROUNDING * inside.abs() {
            return inside;
        }
        let beyond = [(cos[0] - COS_ROUNDING).max(-1.0), (cos[1] + COS_ROUNDING).min(1.0)].map(|c| area(c.acos()));
        extreme(inside, extreme(beyond[0], beyond[1]))
    }
}

/// An upper bound of the angle between directions whose cosines with a normal are `c` and a
/// cosine within `δ` = [`COS_ROUNDING`] of it: within `2δ` of a pole both lie within
/// `acos(1 − 3δ) ≈ √(6δ)` of it; elsewhere `δ` over the smallest sine on the way (mean value
/// theorem, `|acos'| = 1/sin` grows toward the poles).
fn sliver_angle(c: f64) -> f64 {
    let (c, delta) = (c.abs().min(1.0), COS_ROUNDING);
    if 1.0 - c <= 2.0 * delta {
        return 3.0 * delta.sqrt();
    }
    let far = c + delta;
    delta / ((1.0 - far) * (1.0 + far)).sqrt()
}

/// Relative margin of `S_up` and `S_lo` for the rounding of `d·n` (~1e-16) where the bound and
/// `σ_t` compute it apart: in the grazing tail of a smooth lobe `d ln σ / d(d·n) ≈ 2 c/α²`, up to
/// 5e-9 relative per ulp at α = 1e-6 before σ underflows (found by fuzzing: gpss α = 1e-6 at
/// d·n = 1.09e-5 exceeded the majorant by 2.2e-9).
const AREA_ROUNDING: f64 = 1e-7;

/// How far `σ_t`'s `d·n` may lie outside the range the segment bound computed for it (unit vectors
/// rounded apart, a dot product, and the bound's `cos(acos c)`): a few ulps of 1. Near the poles
/// that is an angle of up to 6e-8 rad, over which a rough lobe's area changes by 1e-4 relative
/// (found by fuzzing: GGX α = 1e6 along the normal exceeded the majorant at every collision).
const COS_ROUNDING: f64 = 8.0 * f64::EPSILON;

/// Below this width (radians) a range of directions is bounded from its midpoint: at most a
/// `lipschitz × width / 2` loss, a few percent, for half the evaluations.
const NARROW_RANGE: f64 = 0.05;

/// Tracking of one medium around one mean surface, its parameters constant or given per point by
/// a field ([`crate::field`]).
pub struct Tracker<'a, S: MeanSurface, F: MediumField = Constant> {
    medium: &'a MacrofacetMedium,
    surface: &'a S,
    field: &'a F,
    area: Area<'a>,
    isotropic: bool,
    /// The heights of the whole region: the medium's, or the field's largest `σ`.
    region: HeightProfile,
    /// Whether a collision's uv is completed ([`Self::without_uv`]).
    complete_uv: bool,
    /// The probability with which the caller kept its shadow rays ([`Self::after_roulette`]).
    survival: f64,
    /// Where the calls start, from an earlier collision there ([`Self::from_hint`]; 0: none).
    hint: u64,
}

/// A tracker's projected-area bounds: the host's, or its own (boxed: a tracker is built per
/// call and moved, and the bounds are kilobytes).
enum Area<'a> {
    Borrowed(&'a ProjectedAreaBounds),
    Owned(Box<ProjectedAreaBounds>),
}

impl Area<'_> {
    fn get(&self) -> &ProjectedAreaBounds {
        match self {
            Area::Borrowed(bounds) => bounds,
            Area::Owned(bounds) => bounds,
        }
    }
}

/// Pieces of `d·n` over which [`Tracker::opaque_core`] bounds the projected area, and the ratio of
/// the geometric pieces' ends (the last ends at `|d·n| = 0.95^128 ≈ 1.4e-3`).
const CORE_PIECES: usize = 128;
const CORE_RATIO: f64 = 0.95;

/// The field of a stationary medium.
const CONSTANT: Constant = Constant;

/// What the previous segment of a ray says about the next one's length.
#[derive(Clone, Copy, Debug)]
enum Previous {
    None,
    /// It was empty (above the shell) with this length: try at least twice as long.
    Empty(f64),
    /// It had to be shortened to this length for tight bounds: try at most twice as long.
    Shortened(f64),
}

/// A segment being tracked: where it starts along the ray, its bound and majorant lines.
struct Segment {
    t: f64,
    /// Where the segment starts: the point its bound and tentative collisions are computed from.
    p: DVec3,
    bound: SegmentBound,
    /// The density shape of the majorant and control (the largest `σ` on the segment).
    shape: HeightProfile,
    s_up: f64,
    s_lo: f64,
    /// The field's bounds on the segment (default for a stationary medium).
    params: ParamBounds,
    shortened: bool,
}

impl<'a, S: MeanSurface> Tracker<'a, S> {
    pub fn new(medium: &'a MacrofacetMedium, surface: &'a S) -> Self {
        Tracker::with_field(medium, surface, &CONSTANT)
    }
}

impl<'a, S: MeanSurface, F: MediumField> Tracker<'a, S, F> {
    /// A medium whose parameters `field` gives per point (`σ_max` must bound its `σ`).
    pub fn with_field(medium: &'a MacrofacetMedium, surface: &'a S, field: &'a F) -> Self {
        Self::assemble(medium, Area::Owned(Box::new(ProjectedAreaBounds::new(&medium.phase.ndf))), surface, field)
    }

    /// [`Self::with_field`] with the medium's bounds built beforehand
    /// ([`ProjectedAreaBounds::of`]`(medium)`; bounds of another distribution are not used, the
    /// tracker builds its own).
    pub fn with_bounds(medium: &'a MacrofacetMedium, bounds: &'a ProjectedAreaBounds, surface: &'a S, field: &'a F) -> Self {
        let area = if bounds.source == medium.phase.ndf { Area::Borrowed(bounds) } else { Area::Owned(Box::new(ProjectedAreaBounds::new(&medium.phase.ndf))) };
        Self::assemble(medium, area, surface, field)
    }

    fn assemble(medium: &'a MacrofacetMedium, area: Area<'a>, surface: &'a S, field: &'a F) -> Self {
        let region = HeightProfile { sigma: field.sigma_max().unwrap_or(medium.height.sigma), ..medium.height };
        // (The area's distribution is the medium's: `with_bounds` checks it.)
        Tracker { medium, surface, field, isotropic: area.get().isotropic, area, region, complete_uv: true, survival: 1.0, hint: 0 }
    }

    /// A tracker whose collisions keep the uv the tracker's queries gave (possibly none) instead
    /// of completing it ([`MeanSurface::uv`]): for callers that do not read it, such as the C
    /// ABI, whose collisions carry no uv (a sphere's costs an `atan2` and an `acos`).
    pub fn without_uv(mut self) -> Self {
        self.complete_uv = false;
        self
    }

    /// A tracker whose calls start where a collision of an earlier call was, with that
    /// collision's `hint` ([`TrackedFlight::Scatter`]): the first surface query begins its search
    /// there ([`MeanSurface::seed_cache`]; any value is safe). A collision's escape flight and
    /// shadow rays start so.
    pub fn from_hint(mut self, hint: u64) -> Self {
        self.hint = hint;
        self
    }

    /// A tracker for shadow rays the caller kept with probability `survival` in `(0, 1]` in a
    /// Russian roulette of its own ([`Self::depth_roulette`]): its transmittance estimates are of
    /// `T / survival`, and its own roulette counts that weight (the same estimates as without the
    /// caller's roulette, where the bound lies below [`ROULETTE_THRESHOLD`]). Free flights are
    /// not affected. Errors: a survival outside `(0, 1]`.
    pub fn after_roulette(mut self, survival: f64) -> Result<Self> {
        if !(survival > 0.0 && survival <= 1.0) {
            return Err(Error::new(ErrorKind::InvalidArgument, format!("a roulette's survival must be in (0, 1], got {survival}")));
        }
        self.survival = survival;
        Ok(self)
    }

    /// Seeds a call's fresh cache with the tracker's hint (in place: a mesh's cache is half a
    /// kilobyte, which returning it by value copied).
    #[inline]
    fn seed(&self, cache: &mut S::Cache) {
        if self.hint != 0 {
            self.surface.seed_cache(cache, self.hint);
        }
    }

    fn height(&self) -> &HeightProfile {
        &self.region
    }

    /// The opaque core of this medium about this surface ([`crate::opaque_core`]): for a
    /// stationary medium only (`None` with a varying field, whose bounds hold per segment).
    pub fn opaque_core(&self) -> Option<OpaqueCore> {
        opaque_core(&self.medium.height, self.descent_rate()?)
    }

    /// `κ` of [`crate::opaque_core`] for this medium about this surface (`σ(d) ds >= κ |df|`
    /// wherever a ray descends): for a stationary medium only (`None` with a varying field).
    /// Cheap with bounds built once ([`ProjectedAreaBounds::of`], [`Self::with_bounds`]).
    pub fn descent_rate(&self) -> Option<f64> {
        if self.field.varies() {
            return None;
        }
        Some(self.area.get().descent_rate(self.surface.normal_is_gradient()) / self.surface.lipschitz())
    }

    /// The caller's Russian roulette on a shadow ray that descends from height `f_from` to
    /// `f_to` (conservatively: at most the start's height, at least the deepest the ray
    /// reaches), before it evaluates anything for it: with `u` uniform in `[0, 1)`, the
    /// probability with which the ray is kept ([`roulette_survival`] of
    /// [`descent_transmittance_bound`]), or 0 when it is not (its estimate is 0). A kept ray's
    /// estimate is then [`Self::after_roulette`]'s. `None` as [`Self::descent_rate`].
    pub fn depth_roulette(&self, f_from: f64, f_to: f64, u: f64) -> Option<f64> {
        let bound = descent_transmittance_bound(&self.medium.height, self.descent_rate()?, f_from, f_to);
        let survival = roulette_survival(bound);
        Some(if u < survival { survival } else { 0.0 })
    }

    /// The medium at a point: the field's local parameters (none for a stationary medium).
    fn local(&self, p: DVec3, point: &SurfacePoint) -> Result<LocalParams> {
        if !self.field.varies() {
            return Ok(LocalParams::default());
        }
        let point = SurfacePoint { uv: self.surface.uv(p, point), ..*point };
        let local = self.field.at(p, &point)?;
        local.validate("the medium's field")?;
        Ok(local)
    }

    /// `σ_t` at `p`, where the surface is `point`, for propagation direction `d` (world space),
    /// with the field's parameters there (returned too).
    pub fn sigma_t_at(&self, p: DVec3, point: &SurfacePoint, d: DVec3) -> Result<(f64, LocalParams)> {
        // (A stationary medium without comparing parameters: the comparison's branches on each
        // Option were mispredicted about twice per tentative collision.)
        if !self.field.varies() {
            return Ok((self.sigma_t(point, d), LocalParams::default()));
        }
        let local = self.local(p, point)?;
        if local == LocalParams::default() {
            return Ok((self.sigma_t(point, d), local));
        }
        let frame = Frame::from_normal_tangent(point.normal, point.tangent)?;
        let medium = self.medium.localized(&local, &frame)?;
        Ok((medium.sigma_t(point.f, frame.to_local(d)), local))
    }

    /// `σ_t` of the medium's own (constant) parameters at a surface point for propagation
    /// direction `d` (world space).
    pub fn sigma_t(&self, point: &SurfacePoint, d: DVec3) -> f64 {
        let rho = self.medium.height.density(point.f);
        if rho == 0.0 {
            return 0.0;
        }
        let d_local = if self.isotropic {
            // Only the polar angle matters; skip the tangent's Gram–Schmidt.
            let c = d.dot(point.normal);
            DVec3::new((1.0 - c * c).max(0.0).sqrt(), 0.0, c)
        } else {
            match Frame::from_normal_tangent(point.normal, point.tangent) {
                Ok(frame) => frame.to_local(d),
                Err(_) => return f64::NAN, // unreachable: checked points have unit normals
            }
        };
        rho * self.medium.sigma(d_local)
    }

    #[inline]
    fn checked(&self, point: Result<SurfacePoint>, p: DVec3, stats: &mut TrackStats) -> Result<SurfacePoint> {
        stats.surface_queries += 1;
        point?.validated(p)
    }

    /// The interval of the ray inside the surface's region around the shell
    /// ([`MeanSurface::clip_region`]: its box grown by the shell's top, or tighter), clipped to
    /// `[0, t_max]`. No representable ray point lies beyond
    /// `t = f64::MAX`: the interval ends there (found by fuzzing: a segment across the shell of
    /// a sphere of radius `f64::MAX` ended past it, and a collision came back at `t = +inf`).
    /// With an exit level (`exit_level` finite, [`Self::sample_free_flight_to_exit`]) the region
    /// reaches it instead: it then holds the host's whole region, not only the shell.
    fn clip(&self, origin: DVec3, d: DVec3, t_max: f64, exit_level: f64) -> Option<(f64, f64)> {
        let reach = if exit_level.is_finite() { exit_level } else { self.height().top() };
        self.surface.clip_region(origin, d, t_max.min(f64::MAX), reach)
    }

    /// The length to ask the surface for: enough for `f` to change by [`SEGMENT_SIGMAS`] σ below
    /// where the shell begins, longer across empty space, doubling after an empty segment.
    fn segment_length(&self, start: &SurfacePoint, d: DVec3, previous: Previous) -> f64 {
        let (sigma, top) = (self.height().sigma, self.height().top());
        // Rays within ~7° of the surface are treated as grazing: the bound, not the cosine,
        // then limits the segment.
        let c = d.dot(start.normal);
        let rate = more(c.abs(), 0.125);
        let approach = if start.f > top { (start.f - top) / rate } else { 0.0 };
        let length = approach + SEGMENT_SIGMAS * sigma / rate;
        match previous {
            Previous::None => length,
            Previous::Empty(l) => more(length, 2.0 * l),
            Previous::Shortened(l) => less(length, 2.0 * l),
        }
    }

    /// Far above the shell, steps of `f − top` (the signed distance is 1-Lipschitz, so the shell
    /// cannot begin before): cheaper than bounding a long segment with many candidate features.
    /// Nearer, only steps the surface knows exactly ([`MeanSurface::rising_clearance`]).
    /// Returns the new distance, position and surface point.
    /// Between exact queries the surface's cheap lower bound of `|f|` keeps the steps going: the
    /// ray stays above the top face (`f >= top > 0` after a step of `f − top`), so there `f` is at
    /// least that bound. Stops at the first exact query above `exit_level` (the ray has left the
    /// host's region there: [`Self::sample_free_flight_to_exit`]).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn skip_above(&self, mut t: f64, mut p: DVec3, mut start: SurfacePoint, origin: DVec3, d: DVec3, t_exit: f64, exit_level: f64, cache: &mut S::Cache, stats: &mut TrackStats) -> Result<(f64, DVec3, SurfacePoint)> {
        let (sigma, top) = (self.height().sigma, self.height().top());
        // A surface whose clearance is the crossing itself crosses any gap in one step.
        let exact_clearance = self.surface.exact_clearance();
        let threshold = if exact_clearance { top } else { top + SKIP_SIGMAS * sigma };
        let mut f = start.f;
        let mut exact = true;
        for _ in 0..MAX_SKIPS {
            if !(t < t_exit) || (exact && f > exit_level) {
                break;
            }
            // Between the top face and the threshold, only a step the surface knows exactly.
            if exact && f > top && !(f > threshold) {
                let Some(step) = self.surface.rising_clearance(&start, p, d, top, cache) else { break };
                t += step;
                if !(t < t_exit) {
                    break;
                }
                p = ray_point(origin, t, d)?;
                start = self.checked(self.surface.start_point(p, cache), p, stats)?;
                f = start.f;
                continue;
            }
            if !(f > threshold) {
                break;
            }
            // An exact query knows more than the Lipschitz bound when the surface does.
            t += if exact { self.surface.clearance(&start, p, d, top, cache) } else { f - top };
            if !(t < t_exit) {
                break;
            }
            p = ray_point(origin, t, d)?;
            if exact_clearance {
                // At the crossing (rounded short of it): the shell begins here.
                return Ok((t, p, self.checked(self.surface.start_point(p, cache), p, stats)?));
            }
            f = self.surface.distance_bound(p).max(top);
            exact = false;
            if !(f > threshold) {
                start = self.checked(self.surface.start_point(p, cache), p, stats)?;
                f = start.f;
                exact = true;
            }
        }
        if !exact {
            start = self.checked(self.surface.start_point(p, cache), p, stats)?;
        }
        Ok((t, p, start))
    }

    /// Asks the surface for the bound of the next segment, shortening it while it is loose.
    /// `start` is the surface at `p`, exactly (the tracker never re-derives `p` from `t`: a
    /// segment starts where the last one's bound ended, at `p + length d` as the surface computed
    /// it, and the surface may rely on `start`'s sign there; found by fuzzing: `origin + t d` lay
    /// 2e-16 inside a mesh's edge where the last bound's end point was 3e-17 outside, and the
    /// mesh bounded the segment as outside, a majorant 3 times too low).
    /// (Inlined into the two tracking loops: returned through a `Result`, its `Segment` of
    /// ~280 bytes was copied by `memcpy` at every segment. With it and the three helpers that
    /// return a surface point, the thin sphere anchor renders with 2.5 % fewer instructions,
    /// the torus 2.5 % and the fuzzy sphere of bench/gpis_compare.xml 2.7 %.)
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn next_segment(&self, t: f64, p: DVec3, start: &SurfacePoint, d: DVec3, remaining: f64, previous: Previous, cache: &mut S::Cache, stats: &mut TrackStats) -> Result<Segment> {
        let sigma = self.height().sigma;
        let mut length = less(self.segment_length(start, d, previous), remaining);
        let mut shortenings = 0;
        // The length last halved for looseness, with its looseness; whether that was in vain.
        let (mut longer, mut in_vain): (Option<(f64, f64)>, bool) = (None, false);
        let (mut field_shortenings, mut last_factor) = (0, f64::INFINITY);
        let mut wide_shortenings = 0;
        loop {
            stats.segments += 1;
            let mut bound = self.surface.bound(start, p, d, length, LOOSENESS_SIGMAS * sigma, cache)?;
            bound.validate(length, start.f, "the mean surface")?;
            // The end point is used before the segment ends (found by fuzzing: a convex callback
            // surface's end with an infinite tangent went on for 6 callback calls).
            match bound.end {
                SegmentEnd::Point(end) => {
                    end.validated(p + bound.length * d)?;
                }
                SegmentEnd::Height(f) if f.is_nan() => return Err(nan_end_height(p + bound.length * d)),
                _ => {}
            }
            // A side without a bound gets the surface's Lipschitz bound (validated: only f_lo
            // may be −∞ and only f_hi +∞).
            let lipschitz = SegmentBound::lipschitz(start.f, bound.length, self.surface.lipschitz());
            if bound.f_lo.contains(&f64::NEG_INFINITY) {
                bound.f_lo = lipschitz.f_lo;
            }
            if bound.f_hi.contains(&f64::INFINITY) {
                bound.f_hi = lipschitz.f_hi;
            }
            // The surface is queried at rounded points `origin + t d`: f there may differ from
            // the line through the ends by the rounding of the coordinates and of `t d`, at most
            // linear in between since |q|∞ and t are (found by fuzzing: σ = 1e-50 at
            // |p| ~ 1e-37 broke a plane's exact majorant; so did t = 1e225 from an origin at
            // z = −1e225, where the points near z = −4e221 were off by an ulp of t, 1.5e209).
            let rounding = [(p, t), (p + bound.length * d, t + bound.length)].map(|(q, t)| POSITION_ROUNDING * (largest_magnitude(q) + t));
            if rounding.iter().all(|r| r.is_finite()) {
                bound.f_lo = [bound.f_lo[0] - rounding[0], bound.f_lo[1] - rounding[1]];
                bound.f_hi = [bound.f_hi[0] + rounding[0], bound.f_hi[1] + rounding[1]];
            }
            // How far below f the lower bound falls at the ends (what costs tentative collisions),
            // against the end point's f when the surface gave it, else the upper bound.
            let f_end = bound.end.f().unwrap_or(bound.f_hi[1]);
            // (f64::max: an infinite f at the start, far outside a mesh, makes a difference NaN.)
            let looseness = (start.f - bound.f_lo[0]).max(f_end - bound.f_lo[1]);
            // A halving in vain is undone, asking for the longer segment again (a surface's cache
            // follows its last bound): kept, it would repeat on every segment, as the next one,
            // asked twice as long after an empty one, was halved back (found by fuzzing: σ = 1e-50
            // deep inside a mesh of size 1000, whose padding of 2e-9 stayed, crept on by 1e-50).
            if let Some((halved, halved_looseness)) = longer.take() {
                if !(looseness < SHORTENING_GAIN * halved_looseness) {
                    (length, in_vain) = (halved, true);
                    shortenings -= 1;
                    continue;
                }
            }
            let loose = looseness > LOOSENESS_SIGMAS * sigma;
            // A surface that shortened the segment itself has already weighed cost and tightness.
            if loose && !in_vain && shortenings < MAX_SHORTENINGS && bound.length == length && bound.length > 2.0 * sigma {
                shortenings += 1;
                longer = Some((bound.length, looseness));
                length = 0.5 * bound.length;
                continue;
            }
            // The field's bounds: the majorant's density shape takes the largest σ, times the
            // factor that covers smaller ones; the projected area the largest roughness.
            let params = if self.field.varies() {
                self.field.bounds(p, d, bound.length)?.validated("the medium's field")?
            } else {
                ParamBounds::default()
            };
            let shape = HeightProfile { sigma: params.sigma.map_or(self.medium.height.sigma, |s| s[1]), ..self.medium.height };
            // A wide range of σ inflates the majorant by (σ_hi/σ_lo)²: shorter segments see a
            // narrower range (unless the segment lies above the shell, where nothing scatters),
            // as long as halving helps (a field's own resolution sets a floor).
            let (factor, above) = (params.density_factor(), less(bound.f_lo[0], bound.f_lo[1]) > shape.top());
            if factor > MAX_DENSITY_FACTOR && factor < 0.95 * last_factor && !above && field_shortenings < MAX_FIELD_SHORTENINGS && bound.length == length {
                field_shortenings += 1;
                last_factor = factor;
                length = 0.5 * bound.length;
                continue;
            }
            // (Borrowed: the bounds hold two Ndf values, hundreds of bytes.)
            let fielded;
            let area = match params.alpha {
                Some([_, hi]) => {
                    fielded = ProjectedAreaBounds::new(&self.medium.isotropic_ndf(hi));
                    &fielded
                }
                None => self.area.get(),
            };
            let s_up = area.upper(bound.cos) * factor;
            // A wide range of d·n (a segment through a sphere's centre, where d·n turns from −1
            // to +1) puts grazing frames into S_up, up to ~α above the projected area where the
            // segment starts: when that is loose and the segment expects many tentative
            // collisions, shorten it to about WIDE_RANGE_COLLISIONS of them (found by fuzzing:
            // GGX α = 1e6, σ = 1e50 around a sphere of radius 986 took 1.6e6 of them).
            if bound.cos[1] - bound.cos[0] > WIDE_COS_RANGE && wide_shortenings < MAX_WIDE_SHORTENINGS && bound.length == length {
                let c = d.dot(start.normal).clamp(-1.0, 1.0);
                if s_up > LOOSE_AREA * area.upper([c, c]) * factor {
                    let (f0, slope) = bound.lower_line();
                    let expected = s_up * shape.density_integral(f0, slope, bound.length);
                    if expected > WIDE_RANGE_COLLISIONS {
                        wide_shortenings += 1;
                        let keep = if expected.is_finite() { WIDE_RANGE_COLLISIONS / expected } else { 0.5 };
                        length = (keep * bound.length).max(f64::MIN_POSITIVE);
                        continue;
                    }
                }
            }
            // The control's S_lo is only needed by transmittance; it sets it.
            return Ok(Segment { t, p, bound, shape, s_up, s_lo: 0.0, params, shortened: shortenings + wide_shortenings > 0 });
        }
    }

    /// `σ_t`, the surface point and the local parameters at the tentative collision `s` of
    /// `seg`, counted in `stats`. On a segment whose bound gave no end point (a start there costs
    /// the surface a full query, e.g. a mesh away from its certified regions) the query is a
    /// [`MeanSurface::start_point`]: it leaves in the cache what the next query and a segment
    /// starting there use ([`Self::restarts_at_tentative`]).
    #[inline(always)]
    fn at_tentative(&self, seg: &Segment, s: f64, d: DVec3, cache: &mut S::Cache, stats: &mut TrackStats) -> Result<(f64, SurfacePoint, LocalParams)> {
        let p = ray_point(seg.p, s, d)?;
        let point = if Self::restarts_at_tentative(seg) { self.surface.start_point(p, cache) } else { self.surface.point_on_segment(p, cache) };
        let point = self.checked(point, p, stats)?;
        let (sigma_t, local) = self.sigma_t_at(p, &point, d)?;
        stats.tentative_collisions += 1;
        Ok((sigma_t, point, local))
    }

    /// True when a free flight ends `seg` at a rejected tentative collision (a transmittance at a
    /// residual one) and starts the next segment there: its bound gave no end point, so the next
    /// start would cost a full query, while the tentative collision's is already made, and a
    /// bound from there is tighter than the rest of this one (on a mesh, a Lipschitz bound no
    /// longer than `|f|` at its start). Delta and ratio tracking stay unbiased: each segment's
    /// majorant and control depend only on the ray before it.
    fn restarts_at_tentative(seg: &Segment) -> bool {
        seg.bound.end == SegmentEnd::Unknown
    }

    /// What the next segment needs to know of `seg`: empty (no tentative collision, nothing
    /// below the top), shortened, or neither.
    fn previous(&self, seg: &Segment, tentative: bool) -> Previous {
        if !tentative && self.is_empty(seg) {
            Previous::Empty(seg.bound.length)
        } else if seg.shortened {
            Previous::Shortened(seg.bound.length)
        } else {
            Previous::None
        }
    }

    /// True when the segment's majorant is zero throughout: it lies above the shell.
    fn is_empty(&self, seg: &Segment) -> bool {
        seg.s_up == 0.0 || less(seg.bound.f_lo[0], seg.bound.f_lo[1]) > seg.shape.top()
    }

    /// The majorant `μ(s)` of a segment at `s`.
    fn majorant(&self, seg: &Segment, s: f64) -> f64 {
        let (f0, slope) = seg.bound.lower_line();
        seg.s_up * seg.shape.density(f0 + slope * s)
    }

    /// The control `μ_c(s) <= σ_t` of a segment at `s` (zero without an upper bound of `f`).
    fn control(&self, seg: &Segment, s: f64) -> f64 {
        let (f0, slope) = seg.bound.upper_line();
        if seg.s_lo == 0.0 {
            return 0.0;
        }
        seg.s_lo * seg.shape.density(f0 + slope * s)
    }

    /// The next tentative collision of the majorant after `s` on the segment, or `None` at its
    /// end: inverts `S_up ∫ρ(f_lo)` at an exponential variate.
    #[inline]
    fn next_tentative(&self, seg: &Segment, s: f64, rng: &mut Pcg32) -> Option<f64> {
        if seg.s_up == 0.0 {
            return None;
        }
        let (f0, slope) = seg.bound.lower_line();
        let target = -rng.next_f64_open().ln() / seg.s_up;
        seg.shape.invert_density_integral(f0 + slope * s, slope, seg.bound.length - s, target).map(|ds| s + ds)
    }

    /// Where the segment after `seg` starts (distance and position): where its bound ended.
    #[inline(always)]
    fn advance(&self, seg: &Segment, origin: DVec3, d: DVec3) -> Result<(f64, DVec3)> {
        let t = seg.t + seg.bound.length;
        // A segment below the rounding of t cannot move the ray: the next would be the same
        // (found by fuzzing: σ = 1e-50 with GGX α = 7e5 shortened every segment to 3e-87 at
        // t = 6e-48, and the call spun through all MAX_SEGMENTS).
        if !(t > seg.t) {
            return Err(Error::new(
                ErrorKind::InvalidArgument,
                format!(
                    "tracking from {origin} along {d} stalled at t = {:e}: its segment of {:e} is below the rounding of t (the majorant needs finer steps than f64 resolves there: sigma too small for the roughness or the coordinates)",
                    seg.t, seg.bound.length
                ),
            ));
        }
        // The point the surface computed the end at (`next_segment`).
        Ok((t, ray_point(seg.p, seg.bound.length, d)?))
    }

    /// Where a call goes once `seg` ended without a collision: `Break` with the distance it
    /// reports where it ends there (passed: the ray past the clipped interval, or (`EXITS`) above
    /// the exit level), known from the end's `f` before the surface point there is computed (a
    /// thin shell's calls mostly end so, within their first segment); else `Continue` with where
    /// the next segment starts: its distance, position and surface point (the bound's end point,
    /// the surface's from what the bound left in the cache, or a fresh query).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn after_segment<const EXITS: bool>(&self, seg: &Segment, origin: DVec3, d: DVec3, t_max: f64, t_exit: f64, exit_level: f64, cache: &mut S::Cache, stats: &mut TrackStats) -> Result<ControlFlow<f64, (f64, DVec3, SurfacePoint)>> {
        let (t, p) = self.advance(seg, origin, d)?;
        if let Some(f) = seg.bound.end.f() {
            // (Counted as the query a known end saves.)
            stats.surface_queries += 1;
            if !(t < t_exit) {
                return Ok(ControlFlow::Break(ended::<EXITS>(t_max, t_exit)));
            }
            if EXITS && f > exit_level {
                return Ok(ControlFlow::Break(t));
            }
        }
        let start = match seg.bound.end {
            // Validated with its bound (`next_segment`).
            SegmentEnd::Point(end) => end,
            SegmentEnd::Height(_) => self.surface.end_point(p, cache)?.validated(p)?,
            SegmentEnd::Unknown => self.checked(self.surface.start_point(p, cache), p, stats)?,
        };
        Ok(ControlFlow::Continue((t, p, start)))
    }

    /// Samples a free flight along `origin + t d`, `t ∈ [0, t_max]` (`t_max` may be `+∞`), by
    /// delta tracking against the segment majorants.
    #[inline]
    pub fn sample_free_flight(&self, origin: DVec3, d: DVec3, t_max: f64, rng: &mut Pcg32, stats: &mut TrackStats) -> Result<TrackedFlight> {
        Ok(self.free_flight::<false>(origin, d, t_max, f64::INFINITY, rng, stats)?.0)
    }

    /// [`Self::sample_free_flight`] for a ray inside a host's region boundary that encloses only
    /// points where `f <= exit_level` (the library's enclosures give it:
    /// [`Enclosure::exit_level`]), when no other geometry lies in the box that holds the region
    /// (the surface's bounding box grown by `exit_level`): the flight also ends where the ray is
    /// found outside the region (an exact query above `exit_level`, or past that box), so the
    /// host needs no ray cast for the boundary's exit. Returns the flight and, when it
    /// passed, where it ended (`t_max`, or the exit: the host continues the ray from there,
    /// outside the region). Flights and transmittances are those of the same ray cut at the
    /// boundary's exit: beyond it the shell's density is zero up to the exit point, and the
    /// host's next ray cast finds any re-entry. `exit_level` must be finite and at least the
    /// shell's top.
    ///
    /// [`Enclosure::exit_level`]: crate::surface::Enclosure::exit_level
    pub fn sample_free_flight_to_exit(&self, origin: DVec3, d: DVec3, t_max: f64, exit_level: f64, rng: &mut Pcg32, stats: &mut TrackStats) -> Result<(TrackedFlight, f64)> {
        self.free_flight::<true>(origin, d, t_max, self.checked_exit_level(exit_level)?, rng, stats)
    }

    /// [`Self::transmittance`] cut at the exit of the host's region, as
    /// [`Self::sample_free_flight_to_exit`]: the estimate and where it ended.
    pub fn transmittance_to_exit(&self, origin: DVec3, d: DVec3, t_max: f64, exit_level: f64, rng: &mut Pcg32, stats: &mut TrackStats) -> Result<(f64, f64)> {
        self.transmittance_until::<true>(origin, d, t_max, self.checked_exit_level(exit_level)?, rng, stats)
    }

    fn checked_exit_level(&self, exit_level: f64) -> Result<f64> {
        let top = self.height().top();
        if exit_level.is_finite() && exit_level >= top {
            Ok(exit_level)
        } else {
            Err(Error::new(ErrorKind::InvalidArgument, format!("exit_level must be finite and at least the shell's top ({top:e}), got {exit_level:e}")))
        }
    }

    /// The flight, and where it ended when it passed: `t_max`, or the exit of the host's region
    /// (`EXITS`, at `exit_level`; `+∞` without: the calls without an exit compile without its
    /// checks, a hot path).
    fn free_flight<const EXITS: bool>(&self, origin: DVec3, d: DVec3, t_max: f64, exit_level: f64, rng: &mut Pcg32, stats: &mut TrackStats) -> Result<(TrackedFlight, f64)> {
        // Missing the box that holds the region: outside it from the origin on.
        let Some((t_enter, t_exit)) = self.clip(origin, d, t_max, exit_level) else { return Ok((TrackedFlight::Pass, ended::<EXITS>(t_max, 0.0))) };
        if EXITS && t_enter > 0.0 {
            return Ok((TrackedFlight::Pass, 0.0));
        }
        let mut cache = S::Cache::default();
        self.seed(&mut cache);
        let mut t = t_enter;
        let mut p = ray_point(origin, t, d)?;
        let mut start = self.checked(self.surface.start_point(p, &mut cache), p, stats)?;
        let mut previous = Previous::None;
        let mut budget = 0u64;
        // Segments that start at a rejected tentative collision spend the tentative budget.
        let mut segments = 0;
        while segments < MAX_SEGMENTS {
            (t, p, start) = self.skip_above(t, p, start, origin, d, t_exit, exit_level, &mut cache, stats)?;
            if !(t < t_exit) {
                return Ok((TrackedFlight::Pass, ended::<EXITS>(t_max, t_exit)));
            }
            if EXITS && start.f > exit_level {
                return Ok((TrackedFlight::Pass, t));
            }
            let seg = self.next_segment(t, p, &start, d, t_exit - t, previous, &mut cache, stats)?;
            let mut s = 0.0;
            let mut tentative = false;
            let mut restart = None;
            while let Some(next) = self.next_tentative(&seg, s, rng) {
                s = next;
                tentative = true;
                spend_tentative(&mut budget, origin, d)?;
                let (sigma_t, point, local) = self.at_tentative(&seg, s, d, &mut cache, stats)?;
                let mu = self.majorant(&seg, s);
                if sigma_t > mu * (1.0 + VIOLATION_SLACK) {
                    stats.majorant_violations += 1;
                }
                let p = seg.p + s * d;
                if rng.next_f64() * mu < sigma_t {
                    // A host's normal is taken within 1e-4 of unit length; the collision's
                    // frame is unit (found by fuzzing: length 1.00005 came back). Its uv is
                    // completed where the tracker's queries left it out (MeanSurface::uv).
                    let uv = if self.complete_uv { self.surface.uv(p, &point) } else { point.uv };
                    let point = SurfacePoint { normal: point.normal.normalize(), uv, ..point };
                    return Ok((TrackedFlight::Scatter { t: seg.t + s, point, local, hint: self.surface.hint(&cache) }, seg.t + s));
                }
                // (A tentative collision at the segment's start would not advance the ray.)
                if Self::restarts_at_tentative(&seg) && seg.t + s > seg.t {
                    restart = Some((seg.t + s, p, point));
                    break;
                }
            }
            (t, p, start) = match restart {
                Some(at) => {
                    previous = Previous::None;
                    at
                }
                None => {
                    segments += 1;
                    previous = self.previous(&seg, tentative);
                    match self.after_segment::<EXITS>(&seg, origin, d, t_max, t_exit, exit_level, &mut cache, stats)? {
                        ControlFlow::Break(t_end) => return Ok((TrackedFlight::Pass, t_end)),
                        ControlFlow::Continue(next) => next,
                    }
                }
            };
        }
        Err(too_many_segments())
    }

    /// An unbiased estimate of the transmittance along `origin + t d`, `t ∈ [0, t_max]`, by
    /// residual ratio tracking against the segment majorants and controls.
    pub fn transmittance(&self, origin: DVec3, d: DVec3, t_max: f64, rng: &mut Pcg32, stats: &mut TrackStats) -> Result<f64> {
        Ok(self.transmittance_until::<false>(origin, d, t_max, f64::INFINITY, rng, stats)?.0)
    }

    /// The estimate, and where it ended (as [`Self::free_flight`]; where it reached 0, the
    /// distance reached).
    fn transmittance_until<const EXITS: bool>(&self, origin: DVec3, d: DVec3, t_max: f64, exit_level: f64, rng: &mut Pcg32, stats: &mut TrackStats) -> Result<(f64, f64)> {
        let Some((t_enter, t_exit)) = self.clip(origin, d, t_max, exit_level) else { return Ok((1.0, ended::<EXITS>(t_max, 0.0))) };
        if EXITS && t_enter > 0.0 {
            return Ok((1.0, 0.0));
        }
        let mut cache = S::Cache::default();
        self.seed(&mut cache);
        let mut t = t_enter;
        let mut p = ray_point(origin, t, d)?;
        let mut start = self.checked(self.surface.start_point(p, &mut cache), p, stats)?;
        let mut transmittance = 1.0 / self.survival;
        let mut previous = Previous::None;
        let mut budget = 0u64;
        // Segments that start at a residual tentative collision spend the tentative budget.
        let mut segments = 0;
        while segments < MAX_SEGMENTS {
            (t, p, start) = self.skip_above(t, p, start, origin, d, t_exit, exit_level, &mut cache, stats)?;
            if !(t < t_exit) {
                return Ok((transmittance, ended::<EXITS>(t_max, t_exit)));
            }
            if EXITS && start.f > exit_level {
                return Ok((transmittance, t));
            }
            let mut seg = self.next_segment(t, p, &start, d, t_exit - t, previous, &mut cache, stats)?;
            // The control needs ρ(f_hi; σ) <= ρ(f; σ(p)): only with σ known on the segment (a
            // field whose σ varies there gets none; ratio tracking alone stays unbiased). The
            // projected area is smallest at the smallest roughness.
            seg.s_lo = match seg.params {
                ParamBounds { sigma: Some([lo, hi]), .. } if lo < hi => 0.0,
                ParamBounds { alpha: Some([lo, _]), .. } => ProjectedAreaBounds::new(&self.medium.isotropic_ndf(lo)).lower(seg.bound.cos),
                _ => self.area.get().lower(seg.bound.cos),
            };
            // The control's optical depth, in closed form: over the whole segment at once, or,
            // where the segment may end at a residual tentative collision (as a free flight's,
            // Self::restarts_at_tentative), over the part tracked when it ends.
            let (h0, h_slope) = seg.bound.upper_line();
            let control_depth = |length: f64| if seg.s_lo > 0.0 { seg.s_lo * seg.shape.density_integral(h0, h_slope, length) } else { 0.0 };
            let restartable = Self::restarts_at_tentative(&seg);
            if seg.s_lo > 0.0 && !restartable {
                transmittance *= (-control_depth(seg.bound.length)).exp();
                if !roulette(&mut transmittance, rng) {
                    return Ok((0.0, t));
                }
            }
            let mut s = 0.0;
            let mut tentative = false;
            let mut restart = None;
            while let Some(next) = self.next_tentative(&seg, s, rng) {
                s = next;
                tentative = true;
                spend_tentative(&mut budget, origin, d)?;
                let (mu, mu_c) = (self.majorant(&seg, s), self.control(&seg, s));
                // Thinning: the residual's tentative collisions are those of μ kept with
                // probability (μ − μ_c)/μ; the rest belong to the control, already integrated.
                if !(rng.next_f64() * mu < mu - mu_c) {
                    continue;
                }
                let (sigma_t, point, _) = self.at_tentative(&seg, s, d, &mut cache, stats)?;
                if sigma_t > mu * (1.0 + VIOLATION_SLACK) || sigma_t < mu_c * (1.0 - VIOLATION_SLACK) {
                    stats.majorant_violations += 1;
                }
                transmittance *= (1.0 - (sigma_t - mu_c) / (mu - mu_c)).clamp(0.0, 1.0);
                // Ending the segment here is a stopping time of its tentative collisions: the
                // next segment's are those of a fresh process from here (unbiased).
                if restartable && seg.t + s > seg.t {
                    transmittance *= (-control_depth(s)).exp();
                    restart = Some((seg.t + s, seg.p + s * d, point));
                }
                if !roulette(&mut transmittance, rng) {
                    return Ok((0.0, seg.t + s));
                }
                if restart.is_some() {
                    break;
                }
            }
            (t, p, start) = match restart {
                Some(at) => {
                    previous = Previous::None;
                    at
                }
                None => {
                    if seg.s_lo > 0.0 && restartable {
                        transmittance *= (-control_depth(seg.bound.length)).exp();
                        if !roulette(&mut transmittance, rng) {
                            return Ok((0.0, seg.t + seg.bound.length));
                        }
                    }
                    segments += 1;
                    previous = self.previous(&seg, tentative);
                    match self.after_segment::<EXITS>(&seg, origin, d, t_max, t_exit, exit_level, &mut cache, stats)? {
                        ControlFlow::Break(t_end) => return Ok((transmittance, t_end)),
                        ControlFlow::Continue(next) => next,
                    }
                }
            };
        }
        Err(too_many_segments())
    }
}

/// Where a call that passed ended: at `t_max` without an exit level, else at the end of the
/// clipped interval (`t_max`, or past the box that holds the host's region).
fn ended<const EXITS: bool>(t_max: f64, t_clipped: f64) -> f64 {
    if EXITS {
        t_clipped
    } else {
        t_max
    }
}

/// The point `p + s d` of a ray, refused where it leaves f64's range: no surface query, and no
/// collision, can be represented there (found by fuzzing: a tentative collision beyond a sphere
/// of radius `f64::MAX` had `f = −inf`, broke the majorant and came back at infinity).
/// (Inlined, with the message out of line: every query of the tracker takes a point.)
#[inline]
fn ray_point(p: DVec3, s: f64, d: DVec3) -> Result<DVec3> {
    let q = p + s * d;
    if !q.is_finite() {
        return Err(beyond_f64(p, s, d));
    }
    Ok(q)
}

#[cold]
#[inline(never)]
fn beyond_f64(p: DVec3, s: f64, d: DVec3) -> Error {
    Error::new(ErrorKind::InvalidArgument, format!("the ray from {p} along {d} leaves the range of f64 at {s:e} from there: no point beyond can be represented"))
}

#[cold]
#[inline(never)]
fn nan_end_height(end: DVec3) -> Error {
    Error::new(ErrorKind::InvalidArgument, format!("the mean surface's segment bound gave f = NaN at its end {end}"))
}

/// The probability with which a caller keeps a shadow ray whose transmittance is at most
/// `bound` before tracking it: `bound / `[`ROULETTE_THRESHOLD`] below the threshold, else 1 (a
/// NaN bound keeps it). The tracker's own roulette plays at the same threshold once its
/// estimate falls below it; the caller's plays before anything is evaluated for the ray
/// ([`Tracker::depth_roulette`], [`Tracker::after_roulette`]).
pub fn roulette_survival(bound: f64) -> f64 {
    if bound < ROULETTE_THRESHOLD {
        (bound / ROULETTE_THRESHOLD).max(0.0)
    } else {
        1.0
    }
}

/// Russian roulette on a transmittance estimate below [`ROULETTE_THRESHOLD`]: survives with
/// probability `T / threshold` and continues with `T = threshold` (unbiased). False when killed.
fn roulette(transmittance: &mut f64, rng: &mut Pcg32) -> bool {
    if *transmittance >= ROULETTE_THRESHOLD {
        return true;
    }
    if rng.next_f64() * ROULETTE_THRESHOLD < *transmittance {
        *transmittance = ROULETTE_THRESHOLD;
        true
    } else {
        *transmittance = 0.0;
        false
    }
}

/// Counts one tentative collision of a call against [`MAX_TENTATIVE`].
#[inline]
fn spend_tentative(budget: &mut u64, origin: DVec3, d: DVec3) -> Result<()> {
    *budget += 1;
    if *budget > MAX_TENTATIVE {
        return Err(too_many_tentative(origin, d));
    }
    Ok(())
}

#[cold]
#[inline(never)]
fn too_many_tentative(origin: DVec3, d: DVec3) -> Error {
    Error::new(
        ErrorKind::InvalidArgument,
        format!(
            "tracking from {origin} along {d} needed more than {MAX_TENTATIVE} tentative collisions: the majorant is loose by many orders of magnitude (sigma far below the surface's size or the rounding of the coordinates, or a deep start inside)"
        ),
    )
}

/// The error of a call that took [`MAX_SEGMENTS`] segments.
fn too_many_segments() -> Error {
    Error::new(ErrorKind::InvalidArgument, format!("tracking did not end after {MAX_SEGMENTS} segments (the mean surface's bounds are degenerate)"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ndf::{Beckmann, Ggx, Gpss};

    /// `f32_at_least` is the smallest f32 at or above its argument, across signs, zero, the
    /// subnormals and the ends of f32's range.
    #[test]
    fn f32_at_least_rounds_up_to_the_next_f32() {
        let mut rng = Pcg32::new(11, 5);
        let cases = [0.0, -0.0, 1e-50, -1e-50, 1.0, -1.0, 0.1, -0.1, 1e-40, -1e-40, 3.5e38, -3.5e38, 1e300, -1e300, f64::INFINITY, f64::NEG_INFINITY];
        let random = (0..2000).map(|_| (2.0 * rng.next_f64() - 1.0) * 10f64.powf(90.0 * rng.next_f64() - 45.0));
        for x in cases.into_iter().chain(random) {
            let r = f32_at_least(x);
            assert!(f64::from(r) >= x, "{x:e}: {r:e} is below it");
            // The f32 just below r is below x: r is the smallest.
            let below = if r == f32::NEG_INFINITY { r } else if r > 0.0 { f32::from_bits(r.to_bits() - 1) } else if r == 0.0 { -f32::from_bits(1) } else { f32::from_bits(r.to_bits() + 1) };
            assert!(r == f32::NEG_INFINITY || f64::from(below) < x, "{x:e}: {below:e} below {r:e} is not below it");
        }
        assert!(f32_at_least(f64::NAN).is_nan());
    }

    /// The cells' bounds hold over every range of `d·n` they answer (against the projected area
    /// sampled across the range, any azimuth) and stay within their looseness of the
    /// distribution's own bounds; they answer most narrow ranges of smooth lobes.
    #[test]
    fn cells_bound_the_projected_area_within_their_looseness() {
        let ndfs = [
            Ndf::Beckmann(Beckmann::new(0.3, 0.3).unwrap()),
            Ndf::Beckmann(Beckmann::new(0.05, 0.05).unwrap()),
            Ndf::Beckmann(Beckmann::new(0.1, 0.4).unwrap()),
            Ndf::Ggx(Ggx::new(0.2, 0.2).unwrap()),
            Ndf::Gpss(Gpss::new(0.4, 0.4, 0.4).unwrap()),
            Ndf::Gpss(Gpss::new(0.02, 0.02, 0.5).unwrap()),
        ];
        let mut rng = Pcg32::new(7, 3);
        for ndf in ndfs {
            let bounds = ProjectedAreaBounds::with_cells(&ndf);
            let area = |c: f64, phi: f64| {
                let s = (1.0 - c * c).max(0.0).sqrt();
                ndf.projected_area(DVec3::new(s * phi.cos(), s * phi.sin(), -c))
            };
            let (mut answered, mut narrow) = (0, 0);
            for _ in 0..4000 {
                let (c, width) = (2.0 * rng.next_f64() - 1.0, 10f64.powf(-6.0 + 6.0 * rng.next_f64()));
                let cos = [(c - width).max(-1.0), (c + width).min(1.0)];
                narrow += usize::from(width < 1e-2);
                let points: Vec<f64> = (0..=16).map(|i| area(cos[0] + (cos[1] - cos[0]) * i as f64 / 16.0, std::f64::consts::TAU * rng.next_f64())).collect();
                let (largest, smallest) = points.iter().fold((0.0f64, f64::INFINITY), |(hi, lo), &a| (hi.max(a), lo.min(a)));
                if let Some(upper) = bounds.tabulated(cos, Side::Upper) {
                    answered += usize::from(width < 1e-2);
                    assert!(upper >= largest, "{ndf:?} over {cos:?}: cells' S_up {upper} below the area {largest}");
                    let exact = bounds.upper_exact(cos);
                    assert!(upper <= CELL_LOOSENESS_UPPER * exact * (1.0 + 1e-12), "{ndf:?} over {cos:?}: cells' S_up {upper} against {exact}");
                }
                if let Some(lower) = bounds.tabulated(cos, Side::Lower) {
                    assert!(lower <= smallest, "{ndf:?} over {cos:?}: cells' S_lo {lower} above the area {smallest}");
                    let exact = bounds.lower_exact(cos);
                    assert!(CELL_LOOSENESS_LOWER * lower >= exact * (1.0 - 1e-12), "{ndf:?} over {cos:?}: cells' S_lo {lower} against {exact}");
                }
            }
            if matches!(ndf, Ndf::Beckmann(b) if b.alpha_u == 0.3) || matches!(ndf, Ndf::Gpss(g) if g.alpha_z == 0.4) {
                assert!(answered * 10 > narrow * 7, "{ndf:?}: the cells answered {answered} of {narrow} narrow ranges");
            }
        }
    }
}
