//! The host's side of the tracking calls: a mean surface ([`SurfaceHost`]) and a field of local
//! parameters ([`FieldHost`]) implemented as C callbacks, both reached through the one
//! `user_data` (a [`Host`]) that `mf_track_*` passes to every callback. Each answers honestly
//! for a number of calls drawn from the fuzz input and then lies in a way drawn from it too: a
//! failure code, NaN, a non-unit normal, a bound that excludes the start, values outside the
//! bounds it declared. The targets then check that a lie the library can see ends the call with
//! an error within [`CALLS_AFTER_LIE`] calls, and that one it cannot see still gives finite
//! answers in range.

use crate::input::{dvec3, vec3, Bytes};
use macrofacet_ffi::*;
use glam::DVec3;
use std::ffi::c_void;

/// Most callback calls a tracking call may make after the first answer it can tell is wrong
/// (including that answer's own call; the library checks each answer when it gets it, but a
/// convex bound's end point is checked when the segment is left).
pub const CALLS_AFTER_LIE: usize = 4;

/// The mean surface a callback host computes.
#[derive(Clone, Copy, Debug)]
pub enum Shape {
    Plane { normal: DVec3, offset: f64 },
    Sphere { center: DVec3, radius: f64 },
}

impl Shape {
    /// The signed distance and its gradient at `p`.
    pub fn eval(&self, p: DVec3) -> (f64, DVec3) {
        match *self {
            Shape::Plane { normal, offset } => (normal.dot(p) - offset, normal),
            // (The gradient from the vector scaled first: a tiny one's squares underflow.)
            Shape::Sphere { center, radius } => {
                let v = p - center;
                ((v).length() - radius, (v / v.abs().max_element()).try_normalize().unwrap_or(DVec3::Z))
            }
        }
    }
}

/// Where the tracker's segment bounds of a callback surface come from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BoundSource {
    /// No bound callback, `MF_SURFACE_GENERAL`: the Lipschitz bound.
    Lipschitz,
    /// No bound callback, `MF_SURFACE_CONVEX` (true of both shapes).
    Convex,
    /// No bound callback, `MF_SURFACE_CONCAVE` (true of a plane, a lie for a sphere).
    Concave,
    /// The bound callback: exact lines for a plane, the Lipschitz bound for a sphere.
    Callback,
}

/// How a host lies once its honest calls are used up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lie {
    None,
    /// A non-zero return code.
    Code(i32),
    /// `f` = NaN (point) or a NaN bound.
    Nan,
    /// The normal scaled by this factor (seen beyond the library's 1e-4 tolerance).
    NormalScale(f64),
    /// A non-finite tangent.
    BadTangent(f64),
    /// `f` shifted by this many scene units: plausible, invisible to the library.
    ShiftF(f64),
    /// `f` = ±inf.
    InfiniteF(f64),
    /// A bound whose start interval excludes `f`, or whose length exceeds the one asked for, or
    /// whose cosine range is out of order: inconsistent, so visible.
    Inconsistent(u8),
    /// A bound that is consistent but too tight (`f_lo = f_hi = f` at the start all along):
    /// invisible except as majorant violations.
    TooTight,
    /// Field: parameters outside their domain (sigma <= 0, alpha < 0, unknown bits).
    OutOfDomain(u8),
}

impl Lie {
    /// True when the library can tell the answer is wrong (it must then fail the call).
    pub fn visible(self) -> bool {
        match self {
            Lie::None | Lie::ShiftF(_) | Lie::InfiniteF(_) | Lie::TooTight => false,
            Lie::NormalScale(s) => (s - 1.0).abs() > 1e-4 * 1.01,
            _ => true,
        }
    }

    /// A lie drawn from the fuzz input (mostly none).
    pub fn draw(b: &mut Bytes) -> Lie {
        match b.u8() % 12 {
            0 => Lie::Code(b.choose(&[1, -1, i32::MIN, 7102])),
            1 => Lie::Nan,
            2 => Lie::NormalScale(b.choose(&[0.0, 0.5, 2.0, 1.0 + 1e-3, 1.0 + 5e-5, 1.0 - 5e-5, f64::INFINITY, 1e300])),
            3 => Lie::BadTangent(b.choose(&[f64::NAN, f64::INFINITY])),
            4 => Lie::ShiftF(b.signed_distance(1.0)),
            5 => Lie::InfiniteF(b.choose(&[f64::INFINITY, f64::NEG_INFINITY])),
            6 => Lie::Inconsistent(b.u8()),
            7 => Lie::TooTight,
            8 => Lie::OutOfDomain(b.u8()),
            _ => Lie::None,
        }
    }
}

/// Call counting shared by both hosts: honest for `honest_calls` calls, then `lie` on every one.
#[derive(Clone, Copy, Debug)]
pub struct Script {
    pub lie: Lie,
    pub honest_calls: usize,
    /// Calls of this host's callbacks since the last [`Host::reset`].
    pub calls: usize,
    /// The call that gave the first visible lie.
    pub first_visible_lie: Option<usize>,
}

impl Script {
    pub fn draw(b: &mut Bytes) -> Script {
        let lie = Lie::draw(b);
        let honest_calls = if lie == Lie::None { usize::MAX } else { b.below(24) };
        Script { lie, honest_calls, calls: 0, first_visible_lie: None }
    }

    /// Counts a call; the lie to tell in it, if any. `applies` says whether this callback can
    /// tell this lie (a visible lie it cannot tell is not recorded).
    fn next(&mut self, applies: impl Fn(Lie) -> bool) -> Lie {
        self.calls += 1;
        if self.calls <= self.honest_calls || !applies(self.lie) {
            return Lie::None;
        }
        if self.lie.visible() && self.first_visible_lie.is_none() {
            self.first_visible_lie = Some(self.calls);
        }
        self.lie
    }

    /// Never lies (a lie that never comes, or none).
    pub fn honest(&self) -> bool {
        self.lie == Lie::None || self.honest_calls == usize::MAX
    }
}

/// A mean surface the host computes.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHost {
    pub shape: Shape,
    pub bounds: BoundSource,
    pub script: Script,
}

impl SurfaceHost {
    /// Its answers hold: no lie, and bounds that are true of the shape.
    pub fn honest(&self) -> bool {
        self.script.honest() && !(self.bounds == BoundSource::Concave && matches!(self.shape, Shape::Sphere { .. }))
    }

    /// The box of the shape's interior (`f <= 0`).
    fn interior_box(&self) -> (DVec3, DVec3) {
        match self.shape {
            Shape::Plane { .. } => (DVec3::NEG_INFINITY, DVec3::INFINITY),
            Shape::Sphere { center, radius } => (center - DVec3::splat(radius), center + DVec3::splat(radius)),
        }
    }

    /// Whether the box the callbacks declare contains the interior: a smaller one is a lie the
    /// library cannot see (found by fuzzing: an enclosure of a sphere declared inside a box near
    /// the origin had vertices inside the region).
    pub fn declares_its_box(&self, callbacks: &mf_surface_callbacks) -> bool {
        let (min, max) = self.interior_box();
        dvec3(callbacks.bounds_min).cmple(min).all() && dvec3(callbacks.bounds_max).cmpge(max).all()
    }

    /// The callbacks for `mf_surface_new_callbacks`; the fuzz input sometimes makes them
    /// invalid (no box, a NULL `point`, an unknown `shape`) or declares a box that is not the
    /// surface's.
    pub fn callbacks(&self, b: &mut Bytes) -> mf_surface_callbacks {
        let (min, max) = self.interior_box();
        let (min, max) = match b.u8() % 16 {
            0 => (DVec3::new(b.float(), b.float(), b.float()), DVec3::new(b.float(), b.float(), b.float())),
            1 => (max, min),
            _ => (min, max),
        };
        let shape = match self.bounds {
            BoundSource::Lipschitz | BoundSource::Callback => MF_SURFACE_GENERAL,
            BoundSource::Convex => MF_SURFACE_CONVEX,
            BoundSource::Concave => MF_SURFACE_CONCAVE,
        };
        mf_surface_callbacks {
            point: if b.u8() % 32 == 0 { None } else { Some(surface_point) },
            bound: if self.bounds == BoundSource::Callback { Some(surface_bound) } else { None },
            shape: if b.u8() % 32 == 0 { b.u32() } else { shape },
            bounds_min: vec3(min),
            bounds_max: vec3(max),
        }
    }
}

/// A field of local parameters the host computes: `sigma` in `sigma`, every roughness in
/// `alpha`, varying smoothly in space; it declares `declared` as its bounds.
#[derive(Clone, Copy, Debug)]
pub struct FieldHost {
    /// `MF_LOCAL_*` bits its `at` answers set.
    pub set: u32,
    pub sigma: [f64; 2],
    pub alpha: [f64; 2],
    pub reflectance_scale: [f64; 2],
    /// What its bounds callback answers.
    pub declared: mf_param_bounds,
    pub sigma_max: f64,
    /// The length over which the parameters vary (scene units).
    pub wavelength: f64,
    /// The medium's own `σ` (what an anisotropy is relative to when `σ` is not set).
    pub medium_sigma: f64,
    pub script: Script,
}

impl FieldHost {
    /// A field from the fuzz input over a medium of height deviation `sigma` whose NDF is gpss
    /// when `gpss` (only those take an anisotropy), varying over `scale`: mostly honest bounds,
    /// sometimes bounds its values leave.
    pub fn draw(b: &mut Bytes, sigma: f64, gpss: bool, scale: f64) -> FieldHost {
        let sigma_medium = sigma;
        let mut set = b.u8() as u32 & (MF_LOCAL_SIGMA | MF_LOCAL_ALPHA | MF_LOCAL_ANISOTROPY | MF_LOCAL_REFLECTANCE_SCALE);
        if set & MF_LOCAL_ANISOTROPY != 0 && !gpss && b.u8() % 4 != 0 {
            set &= !MF_LOCAL_ANISOTROPY;
        }
        let ratio = |b: &mut Bytes| b.choose(&[1.0, 1.0 + 1e-12, 1.1, 2.0, 10.0, 1e3]);
        let sigma_lo = sigma * b.log_uniform(-1.0, 1.0);
        let sigma = [sigma_lo, sigma_lo * ratio(b)];
        let alpha_lo = b.positive(-3.0, 1.0);
        let alpha = [alpha_lo, alpha_lo * ratio(b)];
        let reflectance_scale = [b.unit(), 1.0];
        let mut declared = mf_param_bounds {
            set: set & MF_LOCAL_SIGMA | if set & (MF_LOCAL_ALPHA | MF_LOCAL_ANISOTROPY) != 0 { MF_LOCAL_ALPHA } else { 0 },
            sigma_lo: sigma[0],
            sigma_hi: sigma[1],
            alpha_lo: alpha[0],
            alpha_hi: alpha[1],
        };
        // Sometimes bounds that its values leave (a deterministic lie: violations, no error).
        match b.u8() % 16 {
            0 => declared.sigma_hi = sigma[0],
            1 => declared.alpha_hi = alpha[0],
            2 => declared.set = 0,
            _ => {}
        }
        let sigma_max = match b.u8() % 16 {
            0 => 0.0,
            1 => b.float(),
            2 => sigma[0],
            _ => sigma[1] * b.choose(&[1.0, 1.0, 2.0]),
        };
        let wavelength = scale * b.log_uniform(-2.0, 2.0);
        FieldHost { set, sigma, alpha, reflectance_scale, declared, sigma_max, wavelength, medium_sigma: sigma_medium, script: Script::draw(b) }
    }

    /// Its declared bounds and `sigma_max` hold for its values and it never lies.
    pub fn honest(&self) -> bool {
        let d = &self.declared;
        let sigma_ok = self.set & MF_LOCAL_SIGMA == 0
            || d.set & MF_LOCAL_SIGMA != 0 && d.sigma_lo <= self.sigma[0] && self.sigma[1] <= d.sigma_hi && self.sigma[1] <= self.sigma_max;
        let alpha_ok = self.set & (MF_LOCAL_ALPHA | MF_LOCAL_ANISOTROPY) == 0 || d.set & MF_LOCAL_ALPHA != 0 && d.alpha_lo <= self.alpha[0] && self.alpha[1] <= d.alpha_hi;
        self.script.honest() && sigma_ok && alpha_ok
    }

    pub fn callbacks(&self) -> mf_field_callbacks {
        mf_field_callbacks { at: Some(field_at), bounds: Some(field_bounds), sigma_max: self.sigma_max }
    }

    /// A smooth weight in `[0, 1]` at `p` (axis `k` of three independent ones).
    fn weight(&self, p: DVec3, k: usize) -> f64 {
        let x = p[k % 3] / self.wavelength + k as f64;
        (0.5 + 0.5 * x.sin()).clamp(0.0, 1.0)
    }

    fn lerp(range: [f64; 2], w: f64) -> f64 {
        // The ends may come in either order (a range derived from fuzz bytes).
        // (A NaN end, which `positive` may draw, gives NaN: the library must refuse it.)
        let (lo, hi) = (range[0].min(range[1]), range[0].max(range[1]));
        let value = range[0] + (range[1] - range[0]) * w;
        if lo <= hi { value.clamp(lo, hi) } else { value }
    }

    /// The parameters at `p`: every value inside its range.
    pub fn at(&self, p: DVec3) -> mf_local_params {
        let mut out = mf_local_params::NONE;
        out.set = self.set;
        let sigma = Self::lerp(self.sigma, self.weight(p, 0));
        let alpha = DVec3::new(Self::lerp(self.alpha, self.weight(p, 1)), Self::lerp(self.alpha, self.weight(p, 2)), Self::lerp(self.alpha, self.weight(p, 3)));
        if self.set & MF_LOCAL_SIGMA != 0 {
            out.sigma = sigma;
        }
        if self.set & MF_LOCAL_ALPHA != 0 {
            out.alpha = vec3(alpha);
        }
        if self.set & MF_LOCAL_ANISOTROPY != 0 {
            // Σ = diag(2σ²/α²) in world space: the roughness matrix 2σ²Σ⁻¹ has eigenvalues α²
            // in any frame (seeds/004 Eq. 25 with seeds/000 Eq. 4 per axis).
            let s = if self.set & MF_LOCAL_SIGMA != 0 { sigma } else { self.medium_sigma };
            let l2 = |a: f64| 2.0 * s * s / (a * a);
            out.anisotropy = [l2(alpha.x), l2(alpha.y), l2(alpha.z), 0.0, 0.0, 0.0];
        }
        if self.set & MF_LOCAL_REFLECTANCE_SCALE != 0 {
            let r = Self::lerp(self.reflectance_scale, self.weight(p, 4));
            out.reflectance_scale = mf_rgb { r, g: r, b: r };
        }
        out
    }
}

/// What `user_data` points to in the tracking calls.
#[derive(Debug)]
pub struct Host {
    pub surface: Option<SurfaceHost>,
    pub field: Option<FieldHost>,
    /// A built-in surface whose bounds must hold (`crate::surface::Built::exact`).
    pub surface_exact: bool,
}

impl Host {
    pub fn user_data(&mut self) -> *mut c_void {
        self as *mut Host as *mut c_void
    }

    /// Starts counting calls afresh (before each ABI call).
    pub fn reset(&mut self) {
        for s in [self.surface.as_mut().map(|s| &mut s.script), self.field.as_mut().map(|f| &mut f.script)].into_iter().flatten() {
            s.calls = 0;
            s.first_visible_lie = None;
        }
    }

    /// Every answer of both hosts holds.
    pub fn honest(&self) -> bool {
        self.surface_exact && self.surface.as_ref().is_none_or(|s| s.honest()) && self.field.as_ref().is_none_or(|f| f.honest())
    }

    /// Gives the same answers whenever asked (no lie that depends on the call count): batches
    /// then equal single calls.
    pub fn deterministic(&self) -> bool {
        self.surface.as_ref().is_none_or(|s| s.script.honest()) && self.field.as_ref().is_none_or(|f| f.script.honest())
    }

    /// The calls made after the first visible lie of either host (including its own), if one
    /// was told.
    pub fn calls_after_visible_lie(&self) -> Option<usize> {
        [self.surface.as_ref().map(|s| s.script), self.field.as_ref().map(|f| f.script)]
            .into_iter()
            .flatten()
            .filter_map(|s| s.first_visible_lie.map(|first| s.calls - first + 1))
            .max()
    }

    /// Callback calls made since the last reset.
    pub fn calls(&self) -> usize {
        self.surface.as_ref().map_or(0, |s| s.script.calls) + self.field.as_ref().map_or(0, |f| f.script.calls)
    }
}

/// The surface's `point` callback.
unsafe extern "C" fn surface_point(user_data: *mut c_void, p: mf_vec3, out: *mut mf_surface_point) -> i32 {
    let host = &mut *(user_data as *mut Host);
    let s = host.surface.as_mut().expect("a callback surface has a host");
    let lie = s.script.next(|l| !matches!(l, Lie::Inconsistent(_) | Lie::TooTight | Lie::OutOfDomain(_)));
    let (mut f, mut normal) = s.shape.eval(dvec3(p));
    let mut tangent = normal.any_orthonormal_vector();
    match lie {
        Lie::Code(code) => return code,
        Lie::Nan => f = f64::NAN,
        Lie::NormalScale(k) => normal *= k,
        Lie::BadTangent(x) => tangent.x = x,
        Lie::ShiftF(df) => f += df,
        Lie::InfiniteF(x) => f = x,
        _ => {}
    }
    *out = mf_surface_point { f, normal: vec3(normal), tangent: vec3(tangent), u: 0.0, v: 0.0 };
    0
}

/// The surface's `bound` callback: exact for a plane (f is linear, the cosine constant), the
/// Lipschitz bound for a sphere.
unsafe extern "C" fn surface_bound(user_data: *mut c_void, start: *const mf_surface_point, _p: mf_vec3, d: mf_vec3, length: f64, _tolerance: f64, out: *mut mf_segment_bound) -> i32 {
    let host = &mut *(user_data as *mut Host);
    let s = host.surface.as_mut().expect("a callback surface has a host");
    let lie = s.script.next(|l| matches!(l, Lie::Code(_) | Lie::Nan | Lie::Inconsistent(_) | Lie::TooTight));
    let f0 = (*start).f;
    let d = dvec3(d);
    let mut bound = match s.shape {
        Shape::Plane { normal, .. } => {
            let c = d.dot(normal);
            let f1 = f0 + c * length;
            mf_segment_bound { length, f_lo: [f0, f1], f_hi: [f0, f1], cos_lo: c, cos_hi: c }
        }
        Shape::Sphere { .. } => mf_segment_bound { length, f_lo: [f0, f0 - length], f_hi: [f0, f0 + length], cos_lo: -1.0, cos_hi: 1.0 },
    };
    match lie {
        Lie::Code(code) => return code,
        Lie::Nan => bound.f_lo[1] = f64::NAN,
        Lie::Inconsistent(k) => match k % 4 {
            0 => bound.f_lo = [f0 + 1.0 + f0.abs(); 2],
            1 => bound.length = 2.0 * length + 1.0,
            2 => (bound.cos_lo, bound.cos_hi) = (0.5, -0.5),
            _ => bound.length = 0.0,
        },
        Lie::TooTight => {
            bound.f_lo = [f0; 2];
            bound.f_hi = [f0; 2];
        }
        _ => {}
    }
    *out = bound;
    0
}

/// The field's `at` callback.
unsafe extern "C" fn field_at(user_data: *mut c_void, p: mf_vec3, _point: *const mf_surface_point, out: *mut mf_local_params) -> i32 {
    let host = &mut *(user_data as *mut Host);
    let field = host.field.as_mut().expect("a field has a host");
    let lie = field.script.next(|l| matches!(l, Lie::Code(_) | Lie::Nan | Lie::OutOfDomain(_)));
    let mut local = field.at(dvec3(p));
    match lie {
        Lie::Code(code) => return code,
        Lie::Nan => {
            local.set |= MF_LOCAL_SIGMA;
            local.sigma = f64::NAN;
        }
        Lie::OutOfDomain(k) => match k % 3 {
            0 => {
                local.set |= MF_LOCAL_SIGMA;
                local.sigma = -1.0;
            }
            1 => {
                local.set |= MF_LOCAL_ALPHA;
                local.alpha = mf_vec3 { x: -0.1, y: 0.1, z: 0.0 };
            }
            _ => local.set |= 0x100,
        },
        _ => {}
    }
    *out = local;
    0
}

/// The field's `bounds` callback.
unsafe extern "C" fn field_bounds(user_data: *mut c_void, _p: mf_vec3, _d: mf_vec3, _length: f64, out: *mut mf_param_bounds) -> i32 {
    let host = &mut *(user_data as *mut Host);
    let field = host.field.as_mut().expect("a field has a host");
    let lie = field.script.next(|l| matches!(l, Lie::Code(_) | Lie::Inconsistent(_)));
    let mut bounds = field.declared;
    match lie {
        Lie::Code(code) => return code,
        Lie::Inconsistent(k) => match k % 3 {
            0 => {
                bounds.set |= MF_LOCAL_SIGMA;
                (bounds.sigma_lo, bounds.sigma_hi) = (2.0, 1.0);
            }
            1 => {
                bounds.set |= MF_LOCAL_ALPHA;
                bounds.alpha_lo = f64::NAN;
            }
            _ => bounds.set |= MF_LOCAL_REFLECTANCE_SCALE,
        },
        _ => {}
    }
    *out = bounds;
    0
}
