//! A planar GPSS whose `σ` changes across the plane, for the tracker and the GPIS alike (issue
//! 12): the plane `z = 0` as the tracker's mean surface, and the field. Shared by
//! `tests/gpis_fields.rs` and `examples/bench_core.rs`.

use glam::DVec3;
use macrofacet::field::{LocalParams, MediumField, ParamBounds};
use macrofacet::surface::{Aabb, MeanSurface, SegmentBound, SegmentEnd, SurfacePoint};
use macrofacet::Result;

/// The plane `z = 0` (interior below) with the frame `(x, y, z)`: the gpis kernel's axes.
pub struct PlaneSurface;

impl MeanSurface for PlaneSurface {
    type Cache = ();
    fn point(&self, p: DVec3) -> Result<SurfacePoint> {
        Ok(SurfacePoint { f: p.z, normal: DVec3::Z, tangent: DVec3::X, uv: glam::DVec2::new(p.x, p.y) })
    }
    /// Exact: `f` is linear along any segment and `d · n = d_z`.
    fn bound(&self, start: &SurfacePoint, _p: DVec3, d: DVec3, length: f64, _tolerance: f64, _: &mut ()) -> Result<SegmentBound> {
        let f = [start.f, start.f + length * d.z];
        Ok(SegmentBound { length, f_lo: f, f_hi: f, cos: [d.z, d.z], end: SegmentEnd::Unknown })
    }
    fn bounding_box(&self) -> Aabb {
        Aabb { min: DVec3::NEG_INFINITY, max: DVec3::new(f64::INFINITY, f64::INFINITY, 0.0) }
    }
}

/// `σ` changing across the plane `x = 0`: a step from `sigma[0]` to `sigma[1]` (`width = 0`) or
/// a linear ramp over `|x| < width/2`; the roughness stays the medium's, so every lengthscale
/// follows `σ` (seeds/000 Eq. 4 at a fixed `α`).
#[derive(Clone, Copy, Debug)]
pub struct SigmaAcross {
    pub sigma: [f64; 2],
    pub width: f64,
}

impl SigmaAcross {
    pub fn sigma_at(&self, x: f64) -> f64 {
        if self.width == 0.0 {
            return if x < 0.0 { self.sigma[0] } else { self.sigma[1] };
        }
        let s = (x / self.width + 0.5).clamp(0.0, 1.0);
        self.sigma[0] + s * (self.sigma[1] - self.sigma[0])
    }
}

impl MediumField for SigmaAcross {
    fn at(&self, p: DVec3, _: &SurfacePoint) -> Result<LocalParams> {
        Ok(LocalParams { sigma: Some(self.sigma_at(p.x)), ..Default::default() })
    }
    /// `σ` is monotone in `x`: its values at the ends bound it.
    fn bounds(&self, p: DVec3, d: DVec3, length: f64) -> Result<ParamBounds> {
        let (a, b) = (self.sigma_at(p.x), self.sigma_at(p.x + length * d.x));
        Ok(ParamBounds { sigma: Some([a.min(b), a.max(b)]), alpha: None })
    }
    fn sigma_max(&self) -> Option<f64> {
        Some(self.sigma[0].max(self.sigma[1]))
    }
}
