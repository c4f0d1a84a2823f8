//! Linear bounds along a segment from candidate triangles: every triangle's distance `d_T` is
//! convex along a line (the distance to a convex set), so it lies above its tangents and
//! `|plane_T|`, and below its chord; `|f| = min_T d_T` over the candidates.

use super::triangle::{closer, Closest};

/// A candidate triangle's distance at a point of a segment and its derivative along `d`, and
/// the signed distance to its plane with its derivative.
#[derive(Clone, Copy, Debug)]
pub(super) struct Tangent {
    pub closest: Closest,
    pub distance: f64,
    pub slope: f64,
    /// False when rounding makes `slope` too inaccurate for a supporting line.
    pub reliable: bool,
    pub plane: f64,
    pub plane_slope: f64,
}

/// Lower lines of a triangle's convex distance `d_T` along a segment: the tangent at a point
/// of it (`d_T` is convex) and `±` the signed plane distance (`d_T >= |plane|`, exact over the
/// triangle's interior). As (value at 0, slope), lowered by `eps` for rounding.
pub(super) fn lower_lines(t: &Tangent, at: f64, eps: f64) -> [(f64, f64); 3] {
    // Without a reliable derivative, the Lipschitz line falling away from `at` into the segment.
    let tangent_slope = if t.reliable { t.slope } else if at == 0.0 { -1.0 } else { 1.0 };
    [(t.distance, tangent_slope), (t.plane, t.plane_slope), (-t.plane, -t.plane_slope)].map(|(v, k)| (v - k * at - eps, k))
}

/// How far from `s = 0` every candidate keeps a positive lower line (so `|f| > 0`): for each
/// candidate the farthest zero of its lines that start positive (`∞` if one does not decrease),
/// then the nearest over candidates. `None` when some candidate has no line positive at 0.
pub(super) fn positive_until(lines: &[[(f64, f64); 3]]) -> Option<f64> {
    lines.iter().try_fold(f64::INFINITY, |reach: f64, ls| {
        let own = ls.iter().filter(|(v, _)| *v > 0.0).map(|&(v, k)| if k < 0.0 { v / -k } else { f64::INFINITY }).fold(f64::NEG_INFINITY, f64::max);
        (own > 0.0).then_some(reach.min(own))
    })
}

/// The line (of both ends' lower lines) with the largest minimum over `[0, length]`: the bound
/// is a minimum over triangles, so a line that dips anywhere costs there.
pub(super) fn best_lower_line(start: &Tangent, end: &Tangent, length: f64, eps: f64) -> (f64, f64) {
    lower_lines(start, 0.0, eps)
        .into_iter()
        .chain(std::iter::once(lower_lines(end, length, eps)[0]))
        .max_by(|a, b| a.0.min(a.0 + a.1 * length).total_cmp(&b.0.min(b.0 + b.1 * length)))
        .expect("four lines")
}

/// Keeps the elements of `v` whose flag in `keep` is set, in place.
pub(super) fn retain_flagged<V: Retain>(v: &mut V, keep: &[bool]) {
    let mut flags = keep.iter();
    v.retain_each(&mut || *flags.next().expect("one flag per element"));
}

/// What [`retain_flagged`] needs of a vector: `Vec` and `SmallVec` keep elements in place.
pub(super) trait Retain {
    fn retain_each(&mut self, keep: &mut dyn FnMut() -> bool);
}

impl<T> Retain for Vec<T> {
    fn retain_each(&mut self, keep: &mut dyn FnMut() -> bool) {
        self.retain(|_| keep());
    }
}

impl<A: smallvec::Array> Retain for smallvec::SmallVec<A> {
    fn retain_each(&mut self, keep: &mut dyn FnMut() -> bool) {
        self.retain(|_| keep());
    }
}

/// Whether a triangle can be the closest one somewhere on a segment of `length`: its distance
/// lies above both end tangents (convex; Lipschitz lines where the derivative is unreliable),
/// and the closest distance below the tent `min(tent.0 + s, tent.1 + length − s)`. Both are
/// piecewise linear, so comparing them at the break points decides.
pub(super) fn may_be_closest(start: &Tangent, end: &Tangent, tent: (f64, f64), length: f64, eps: f64) -> bool {
    let l0 = lower_lines(start, 0.0, eps)[0];
    let l1 = lower_lines(end, length, eps)[0];
    let lower = |s: f64| (l0.0 + l0.1 * s).max(l1.0 + l1.1 * s);
    let upper = |s: f64| (tent.0 + s).min(tent.1 + length - s) + eps;
    let apex = 0.5 * (tent.1 + length - tent.0);
    let cross = if l0.1 != l1.1 { (l1.0 - l0.0) / (l0.1 - l1.1) } else { 0.0 };
    [0.0, length, apex, cross].into_iter().filter(|s| (0.0..=length).contains(s)).any(|s| lower(s) <= upper(s))
}

/// The closest point among the candidates' tangents.
pub(super) fn closest_of(tangents: &[Tangent]) -> Closest {
    tangents.iter().map(|t| t.closest).reduce(|best, c| if closer(&c, &best) { c } else { best }).expect("candidates are not empty")
}
