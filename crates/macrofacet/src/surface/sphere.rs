//! A sphere as a mean surface: `f = |p − c| − r` (negated with flipped normals), the frame normal
//! is `∇f` and the tangent Mitsuba 3's `dp/du = pole × (p − c)` (its `u` runs around the pole,
//! the object's `+z` axis), so anisotropic roughness follows the same direction in both renderers.

use super::{convex_bound, Aabb, Curvature, MeanSurface, SegmentBound, SurfacePoint};
use crate::error::{check_positive, Error, ErrorKind, Result};
use crate::frame::{check_finite_vector, length_and_direction, rescaled, robust_length};
use glam::{DVec2, DVec3};
use std::f64::consts::{PI, TAU};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    pub center: DVec3,
    pub radius: f64,
    /// Normals point inward: the "interior" is everything outside the sphere.
    pub flip_normals: bool,
    /// Unit axis of the `u` parametrization (the object's `+z` in world space).
    pub pole: DVec3,
}

impl Sphere {
    pub fn new(center: DVec3, radius: f64, flip_normals: bool, pole: DVec3) -> Result<Sphere> {
        check_finite_vector("center", center)?;
        check_positive("radius", radius, false)?;
        check_finite_vector("pole", pole)?;
        // Rescaled first, like the normals of `point` (found by fuzzing: a pole of length 1.8e-162
        // became a normal of length 1.0000118 at the centre).
        let pole = rescaled(pole).try_normalize().ok_or_else(|| Error::new(ErrorKind::InvalidArgument, "pole must not be the zero vector"))?;
        Ok(Sphere { center, radius, flip_normals, pole })
    }

    /// [`MeanSurface::point`] but for `uv` (zero): the tracker's queries, where the two angles
    /// of the uv would cost as much as the rest ([`MeanSurface::uv`]).
    #[inline]
    fn point_without_uv(&self, p: DVec3) -> SurfacePoint {
        // Where `|v|` is finite it gives the direction too, with one square root in the common
        // case ([`Self::distance`] halves `v` otherwise).
        let v = p - self.center;
        let (length, direction) = length_and_direction(v);
        let (v, distance, direction) = if length.is_finite() {
            (v, length - self.radius, direction)
        } else {
            let (half, distance) = self.distance(p);
            (half, distance, rescaled(half).try_normalize())
        };
        // At the centre every direction is a gradient; any unit vector keeps the frame valid.
        // Rescaled first: |v|² of a v shorter than 1e-154 loses its precision to underflow (a
        // point 4e-163 from the centre had a normal of length 0.9999955, found by fuzzing).
        let outward = direction.unwrap_or(self.pole);
        SurfacePoint { f: self.sign() * distance, normal: self.sign() * outward, tangent: self.pole.cross(v), uv: DVec2::ZERO }
    }

    /// `|p − c| − r` with the offset it came from ([`Self::offset`]).
    fn distance(&self, p: DVec3) -> (DVec3, f64) {
        let (v, scale, length) = self.offset(p);
        let distance = if scale == 1.0 { length - self.radius } else { scale * (length - self.radius / scale) };
        (v, distance)
    }

    /// `p − c` as `scale × v` (`scale` 1, or 2 where `p − c` or its length would overflow) with
    /// `|v|`, without overflow: `|p − c|²` overflows from 1.3e154 on (found by fuzzing: a flipped
    /// sphere answered f = −inf 1.4e284 from its centre), and `|p − c|` itself near `f64::MAX`,
    /// where `|p − c| − r` may still be small (found by fuzzing: a point on the shell of a sphere
    /// of radius `f64::MAX` had f = −inf and broke the majorant). So `f` is `scale (|v| − r /
    /// scale)`, infinite only where the distance to the sphere is.
    fn offset(&self, p: DVec3) -> (DVec3, f64, f64) {
        let v = p - self.center;
        let length = robust_length(v);
        if length.is_finite() {
            return (v, 1.0, length);
        }
        let half = 0.5 * p - 0.5 * self.center;
        (half, 2.0, robust_length(half))
    }

    fn sign(&self) -> f64 {
        if self.flip_normals {
            -1.0
        } else {
            1.0
        }
    }
}

impl MeanSurface for Sphere {
    type Cache = ();

    fn point(&self, p: DVec3) -> Result<SurfacePoint> {
        let point = self.point_without_uv(p);
        Ok(SurfacePoint { uv: self.uv(p, &point), ..point })
    }

    fn start_point(&self, p: DVec3, _: &mut ()) -> Result<SurfacePoint> {
        Ok(self.point_without_uv(p))
    }

    fn point_on_segment(&self, p: DVec3, _: &()) -> Result<SurfacePoint> {
        Ok(self.point_without_uv(p))
    }

    /// Mitsuba's sphere uv (azimuth / 2π, polar angle / π) about the pole, the azimuth measured
    /// from the first vector of the pole's Duff et al. basis.
    fn uv(&self, p: DVec3, _: &SurfacePoint) -> DVec2 {
        let (v, _, _) = self.offset(p);
        let (x_axis, y_axis) = self.pole.any_orthonormal_pair();
        let azimuth = v.dot(y_axis).atan2(v.dot(x_axis));
        let u = if azimuth < 0.0 { azimuth / TAU + 1.0 } else { azimuth / TAU };
        let outward = rescaled(v).try_normalize().unwrap_or(self.pole);
        DVec2::new(u, outward.dot(self.pole).clamp(-1.0, 1.0).acos() / PI)
    }

    fn bound(&self, start: &SurfacePoint, p: DVec3, d: DVec3, length: f64, _tolerance: f64, _: &mut ()) -> Result<SegmentBound> {
        let end = self.point_without_uv(p + length * d);
        let curvature = if self.flip_normals { Curvature::Concave } else { Curvature::Convex };
        let mut bound = convex_bound(start, &end, d, length, curvature);
        let coordinates = p.abs().max((p + length * d).abs()).max(self.center.abs()).max_element();
        // f = |q − c| − r itself is rounded by a few ulps of the coordinates and of r, which for a
        // sphere far larger than its shell exceeds σ (found by fuzzing: a sphere of radius 1.8e308
        // around (0, 2, 1.8e308) answered f = 0 at a point 1e49 outside, σ = 1e50, and the
        // majorant was broken). The bounds of f widen by that (the tracker adds the rounding of
        // the points themselves).
        let f_rounding = 8.0 * f64::EPSILON * coordinates.max(self.radius);
        // The normal (q − c)/|q − c| at a point q of the segment is rounded with q's coordinates,
        // by up to ~4ε × coordinates / |q − c| (found by fuzzing: a flipped sphere of radius 3e49
        // around (−1e300, −1e300, −1e300), tracked from its centre: a point 1.4e284 along the
        // ray was rounded by 1.5e284, its normal 60° off the segment's d·n range, and the
        // majorant broken). The range widens by that at the segment's closest approach to the
        // centre (as the mesh's does at a piece's smallest distance). That distance is at least
        // r plus the lower bound of f on the segment (r minus the upper bound, flipped), less
        // twice the rounding of f and of the points: taken without a square root unless it
        // leaves less than r/2 (a segment reaching toward the centre).
        let near_side = if self.flip_normals { -bound.f_hi[0].max(bound.f_hi[1]) } else { bound.f_lo[0].min(bound.f_lo[1]) };
        let at_least = self.radius + near_side - 2.0 * f_rounding;
        let closest = if at_least > 0.5 * self.radius {
            at_least
        } else {
            let (v, scale, _) = self.offset(p);
            scale * robust_length(v + (-v.dot(d)).clamp(0.0, length / scale) * d)
        };
        let rounding = 4.0 * f64::EPSILON * coordinates / closest;
        if rounding > 0.0 {
            bound.cos = [(bound.cos[0] - rounding).max(-1.0), (bound.cos[1] + rounding).min(1.0)];
        }
        bound.f_lo = bound.f_lo.map(|f| f - f_rounding);
        bound.f_hi = bound.f_hi.map(|f| f + f_rounding);
        Ok(bound)
    }

    /// The distance to the level sphere `|p − c| = r ± level`, shortened by the rounding of
    /// the root: exact, so the tracker skips with it right above the shell
    /// ([`MeanSurface::exact_clearance`]).
    fn clearance(&self, start: &SurfacePoint, p: DVec3, d: DVec3, level: f64, _: &mut ()) -> f64 {
        let lipschitz = start.f - level;
        let v = p - self.center;
        let radius = self.radius + self.sign() * level;
        // (Where |v|² or the radius² overflow, the Lipschitz step stays.)
        if !(radius > 0.0 && (v.length_squared() + radius * radius).is_finite()) {
            return lipschitz;
        }
        let b = v.dot(d);
        // |v|² − radius² as (|v| − radius)(|v| + radius), its first factor ±(f − level): without
        // the cancellation of the difference of squares right above the level.
        let c = self.sign() * lipschitz * (self.radius + self.sign() * start.f + radius);
        let discriminant = b * b - c;
        let exact = if self.flip_normals {
            // Inside the level sphere: the exit.
            -b + discriminant.max(0.0).sqrt()
        } else if discriminant < 0.0 || b >= 0.0 {
            f64::INFINITY // the ray misses the level sphere or moves away from it
        } else {
            // The nearer root, written without cancellation.
            c / (-b + discriminant.sqrt())
        };
        (exact * (1.0 - 1e-9)).max(lipschitz)
    }

    fn exact_clearance(&self) -> bool {
        true
    }

    fn normal_is_gradient(&self) -> bool {
        true
    }

    fn distance_bound(&self, p: DVec3) -> f64 {
        self.distance(p).1.abs()
    }

    /// The chord of the sphere of radius `R = r + 2 reach`, grown by 1e-9 of it (the rounding of
    /// `f` and of the chord, ~1e-16 |o − c|² in `R²`). Twice the reach: a segment that leaves the
    /// shell then ends above its top, where the optical depth's closed form is a constant, not
    /// ~250 instructions. From beyond 1e3 radii, where `|o − c|² − R²` cancels, where `1e6 R²`
    /// overflows, and around a flipped sphere (its region is unbounded), the box. (Cheaper than
    /// the box's three divisions.)
    fn clip_region(&self, o: DVec3, d: DVec3, t_max: f64, reach: f64) -> Option<(f64, f64)> {
        let radius = (self.radius + 2.0 * reach) * (1.0 + 1e-9);
        let oc = o - self.center;
        let (oo, limit) = (oc.length_squared(), 1e6 * radius * radius);
        if self.flip_normals || !(limit.is_finite() && oo <= limit) {
            return self.bounding_box().clip_region(o, d, t_max, reach);
        }
        let b = oc.dot(d);
        let disc = b * b - (oo - radius * radius);
        if !(disc >= 0.0) {
            return None;
        }
        let root = disc.sqrt();
        let (lo, hi) = ((-b - root).max(0.0), (-b + root).min(t_max));
        (lo <= hi).then_some((lo, hi))
    }

    fn bounding_box(&self) -> Aabb {
        if self.flip_normals {
            Aabb::EVERYTHING
        } else {
            Aabb { min: self.center - DVec3::splat(self.radius), max: self.center + DVec3::splat(self.radius) }
        }
    }
}
