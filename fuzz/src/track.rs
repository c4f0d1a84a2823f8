//! The tracking calls with their property checked, shared by the `tracking` and `fields`
//! targets: `mf_track_free_flight`, `mf_track_transmittance`, their batches, `mf_track_depth_roulette`, `mf_surface_eval`,
//! `mf_surface_bounding_box` and `mf_surface_enclosure` on a medium, a surface and (sometimes) a
//! field from the fuzz input, with queries biased toward the surface, its box and the shell.
//!
//! Beyond [`check`]'s property of every call: the callbacks' lies ([`crate::host`]) that the
//! library can see end the call with an error within [`CALLS_AFTER_LIE`] callback calls; an
//! honest surface and field never break a majorant (`stats.majorant_violations == 0`); a batch
//! equals its single calls bit for bit when the host answers the same whenever asked.

use crate::build::Medium;
use crate::check;
use crate::host::{Host, CALLS_AFTER_LIE};
use crate::input::{dvec3, vec3, Bytes};
use crate::surface::Surface;
use glam::DVec3;
use macrofacet_ffi::*;
use std::ptr;

/// An `mf_field`, freed on drop.
pub struct Field(pub *mut mf_field);

impl Drop for Field {
    fn drop(&mut self) {
        // SAFETY: from mf_field_new_callbacks, freed once.
        unsafe { mf_field_free(self.0) };
    }
}

/// What the tracking calls take, and where the surface is (for the queries).
pub struct Scene<'a> {
    pub medium: &'a Medium,
    pub surface: &'a Surface,
    pub field: Option<&'a Field>,
    pub host: Host,
    pub center: DVec3,
    pub size: f64,
}

fn debug() -> bool {
    std::env::var_os("MF_FUZZ_DEBUG").is_some()
}

impl Scene<'_> {
    fn field_ptr(&self) -> *const mf_field {
        self.field.map_or(ptr::null(), |f| f.0 as *const mf_field)
    }

    /// Runs one ABI call that takes the host's `user_data`, then checks the lie rule: a visible
    /// lie must fail it, within [`CALLS_AFTER_LIE`] callback calls.
    fn with_host<T>(&mut self, what: &str, call: impl FnOnce(*mut std::ffi::c_void) -> Result<T, mf_status>) -> Result<T, mf_status> {
        self.host.reset();
        let result = call(self.host.user_data());
        if let Some(after) = self.host.calls_after_visible_lie() {
            assert!(result.is_err(), "{what}: the host's visible lie {:?} was accepted", self.host);
            assert!(after <= CALLS_AFTER_LIE, "{what}: {after} callback calls from the first visible lie on ({:?})", self.host);
        }
        result
    }

    /// `mf_surface_eval` at `p`: a finite `f`, unit normal, finite tangent and uv.
    pub fn eval(&mut self, p: DVec3) -> Option<mf_surface_point> {
        let s = self.surface.0 as *const mf_surface;
        let point = self.with_host("mf_surface_eval", |u| check::call(|o| unsafe { mf_surface_eval(s, u, vec3(p), o) })).ok()?;
        // (±inf allowed: a host may answer it, which the tracking calls take as well, and a
        // distance above ~1e154 overflows in |p - c|, the IEEE answer issue 9 accepts.)
        assert!(!point.f.is_nan(), "mf_surface_eval at {p}: f = {}", point.f);
        if self.host.surface.is_some() {
            // A host's normal passes within the tracker's 1e-4 (hosts compute in f32).
            let len = dvec3(point.normal).length();
            assert!((len - 1.0).abs() <= 1.01e-4, "mf_surface_eval at {p:?}: normal {:?}, length {len}", point.normal);
        } else {
            check::unit(&format!("mf_surface_eval at {p:?}: normal"), point.normal);
        }
        assert!(dvec3(point.tangent).is_finite() && point.u.is_finite() && point.v.is_finite(), "mf_surface_eval at {p}: {point:?}");
        Some(point)
    }

    /// A query: the origin near the surface (on it, on its box, inside, far) or anywhere, the
    /// direction mostly unit and sometimes grazing the surface there, the length from 0 to +inf.
    pub fn query(&mut self, b: &mut Bytes) -> mf_track_query {
        let (c, size) = (self.center, self.size);
        let origin = match b.u8() % 8 {
            0 => DVec3::new(b.float(), b.float(), b.float()),
            1 => c + b.sphere() * size * b.choose(&[1.0, 1.0 + 1e-12, 1.0 - 1e-12, 0.0, 2.0, 3f64.sqrt()]),
            2 => c + DVec3::new(b.signed_distance(size), b.signed_distance(size), b.signed_distance(size)),
            _ => c + b.sphere() * size * b.log_uniform(-2.0, 1.0),
        };
        let normal = if origin.is_finite() { self.eval(origin).map_or(DVec3::Z, |p| dvec3(p.normal)) } else { DVec3::Z };
        let (d, t_max, seed) = (vec3(b.direction(normal)), b.length(size), b.u64());
        // Every fourth query finds its exit above an exit level from the shell's top to 2.75
        // times it, drawn from the seed's bits (the committed inputs' bytes keep their meaning).
        let exit_level = if seed % 4 == 0 { self.shell_top() * (1.0 + (seed >> 2 & 7) as f64 / 4.0) } else { 0.0 };
        // Every fourth query carries a hint (any value is valid: most name no triangle of a small
        // mesh, the rest a foreign one), also from the seed's bits.
        let hint = if seed >> 5 & 3 == 0 { (seed >> 8) % 4096 } else { 0 };
        let q = mf_track_query { origin: vec3(origin), d, t_max, seed, exit_level, survival: 0.0, hint };
        if debug() {
            eprintln!("query: {q:?}");
        }
        q
    }

    /// `mf_medium_shell_top` (0 where it fails: the query then finds no exit).
    fn shell_top(&self) -> f64 {
        let mut top = 0.0;
        // SAFETY: a live medium and a valid out-pointer.
        let _ = unsafe { mf_medium_shell_top(self.medium.0 as *const mf_medium, &mut top) };
        top
    }

    /// One free flight with its property; `honest`: no majorant violation.
    pub fn free_flight(&mut self, q: &mf_track_query) -> Option<mf_collision> {
        let (m, s, f) = (self.medium.0 as *const mf_medium, self.surface.0 as *const mf_surface, self.field_ptr());
        let c = self.with_host("mf_track_free_flight", |u| check::call(|o| unsafe { mf_track_free_flight(m, s, f, u, q, o) })).map_err(|e| { if debug() { eprintln!("free flight error {e:?}: {}", check::last_error()); } }).ok()?;
        if debug() {
            eprintln!("collision: {c:?}");
        }
        check::collision(&c, q);
        self.honest_stats(&c.stats);
        Some(c)
    }

    /// One transmittance estimate with its property.
    pub fn transmittance(&mut self, q: &mf_track_query) -> Option<mf_transmittance> {
        let (m, s, f) = (self.medium.0 as *const mf_medium, self.surface.0 as *const mf_surface, self.field_ptr());
        let t = self.with_host("mf_track_transmittance", |u| check::call(|o| unsafe { mf_track_transmittance(m, s, f, u, q, o) })).map_err(|e| { if debug() { eprintln!("transmittance error {e:?}: {}", check::last_error()); } }).ok()?;
        if debug() {
            eprintln!("transmittance: {t:?}");
        }
        check::transmittance(t.transmittance);
        check::ended(t.t, q);
        self.honest_stats(&t.stats);
        Some(t)
    }

    fn honest_stats(&self, stats: &mf_track_stats) {
        if self.host.honest() {
            assert!(stats.majorant_violations == 0, "an honest surface and field broke a majorant: {stats:?}, host {:?}", self.host);
        }
    }

    /// Both batches: equal to the single calls bit for bit (when the host answers the same
    /// whenever asked), or an error naming a query with nothing written.
    pub fn batches(&mut self, queries: &[mf_track_query]) {
        let (m, s, f) = (self.medium.0 as *const mf_medium, self.surface.0 as *const mf_surface, self.field_ptr());
        let n = queries.len();
        let deterministic = self.host.deterministic();
        let collisions = self.with_host("mf_track_free_flight_batch", |u| check::call_array(n, |o| unsafe { mf_track_free_flight_batch(m, s, f, u, queries.as_ptr(), n, o) }));
        match collisions {
            Ok(out) => {
                for (q, c) in queries.iter().zip(&out) {
                    check::collision(c, q);
                    if deterministic {
                        let single = self.free_flight(q).expect("the batch was fine");
                        assert_eq!(format!("{c:?}"), format!("{single:?}"), "free flight batch vs single");
                    }
                }
            }
            Err(_) => assert!(check::last_error().starts_with("query "), "{}", check::last_error()),
        }
        let transmittances = self.with_host("mf_track_transmittance_batch", |u| check::call_array(n, |o| unsafe { mf_track_transmittance_batch(m, s, f, u, queries.as_ptr(), n, o) }));
        match transmittances {
            Ok(out) => {
                for (q, t) in queries.iter().zip(&out) {
                    check::transmittance(t.transmittance);
                    if deterministic {
                        let single = self.transmittance(q).expect("the batch was fine");
                        assert_eq!(format!("{t:?}"), format!("{single:?}"), "transmittance batch vs single");
                    }
                }
            }
            Err(_) => assert!(check::last_error().starts_with("query "), "{}", check::last_error()),
        }
        // An empty batch may have NULL arrays.
        check::call_array::<mf_collision>(0, |o| unsafe { mf_track_free_flight_batch(m, s, f, ptr::null_mut(), ptr::null(), 0, o) }).expect("empty batch");
        check::call_array::<mf_transmittance>(0, |o| unsafe { mf_track_transmittance_batch(m, s, f, ptr::null_mut(), ptr::null(), 0, o) }).expect("empty batch");
    }

    /// `mf_surface_bounding_box`: ordered, not NaN.
    pub fn bounding_box(&self) -> (DVec3, DVec3) {
        let s = self.surface.0 as *const mf_surface;
        let (mut min, mut max) = (vec3(DVec3::NAN), vec3(DVec3::NAN));
        check::status(unsafe { mf_surface_bounding_box(s, &mut min, &mut max) }).expect("mf_surface_bounding_box");
        let (min, max) = (dvec3(min), dvec3(max));
        assert!((0..3).all(|i| min[i] <= max[i]), "bounding box {min} .. {max}");
        (min, max)
    }

    /// `mf_surface_enclosure` of `f < level` with coarse cells (a fine one costs up to 512³/8
    /// queries), and its mesh: finite positions, indices in range, every vertex outside the
    /// region (the enclosure is conservative: its vertices are corners of cells without region).
    pub fn enclosure(&mut self, b: &mut Bytes, level: f64) {
        let s = self.surface.0 as *const mf_surface;
        let level = if b.u8() % 8 == 0 { b.float() } else { level };
        // Cells relative to the region's extent (the surface's bounding box plus the level: a
        // level 1e3 sizes out, or a surface far larger than the drawn size, took 512 cells per
        // axis and most of the target's time), and the default (0: 1/128 of the extent, ~65 ms
        // for a torus) drawn rarely.
        let (min, max) = self.bounding_box();
        let box_extent = if (max - min).is_finite() { (max - min).max_element() } else { self.size };
        let extent = (box_extent + level.abs()).min(f64::MAX);
        let cell = match b.u8() {
            0 => 0.0,
            1..=31 => b.choose(&[f64::NAN, -1.0, f64::INFINITY]),
            _ => extent * b.log_uniform(-1.5, 0.0),
        };
        if debug() {
            eprintln!("enclosure: level {level:e} cell {cell:e}");
        }
        let Ok(e) = self.with_host("mf_surface_enclosure", |u| check::call(|o| unsafe { mf_surface_enclosure(s, u, level, cell, o) })) else { return };
        let mesh = check::call(|o| unsafe { mf_enclosure_mesh(e, o) }).expect("mf_enclosure_mesh");
        assert!(mesh.normals.is_null() && mesh.uvs.is_null());
        // SAFETY: the arrays live until mf_enclosure_free, sized as the mesh says.
        let (positions, indices) = unsafe {
            (
                if mesh.vertex_count == 0 { &[][..] } else { std::slice::from_raw_parts(mesh.positions, 3 * mesh.vertex_count) },
                if mesh.triangle_count == 0 { &[][..] } else { std::slice::from_raw_parts(mesh.indices, 3 * mesh.triangle_count) },
            )
        };
        assert!(indices.iter().all(|i| (*i as usize) < mesh.vertex_count), "enclosure index out of range");
        let honest = self.host.honest();
        // The exit level: a number at least the level, above every vertex's f (checked below).
        let exit_level = check::call(|o| unsafe { mf_enclosure_exit_level(e, o) }).expect("mf_enclosure_exit_level");
        assert!(!exit_level.is_nan() && exit_level >= level, "exit level {exit_level} for level {level}");
        // A vertex may sit a hair inside for rounding: 1e-9 of the surface's extent (else of the
        // drawn size), or of the vertex's coordinates where that is not a number (the drawn size
        // is NaN when the surface ignores it: a sphere of radius 3.6e250 had every vertex flagged,
        // f = 8e248 against level 0).
        let slack_at = |v: DVec3| 1e-9 * (level.abs() + if box_extent.is_finite() { box_extent } else { v.abs().max_element() });
        // Every vertex finite; at most ~1000 of them (evenly spread) evaluated: a fine enclosure
        // has 1e5 vertices, and evaluating each took most of the target's time.
        let stride = (mesh.vertex_count / 1000).max(1);
        for (k, v) in positions.chunks_exact(3).enumerate() {
            let v = DVec3::from_slice(v);
            assert!(v.is_finite(), "enclosure vertex {v}");
            if honest && k % stride == 0 {
                let slack = slack_at(v);
                if let Some(p) = self.eval(v) {
                    assert!(p.f >= level - slack, "enclosure vertex {v} inside the region: f = {} < level {level}", p.f);
                    assert!(p.f <= exit_level + slack, "enclosure vertex {v} above the exit level: f = {} > {exit_level}", p.f);
                }
            }
        }
        // SAFETY: from mf_surface_enclosure, freed once.
        unsafe { mf_enclosure_free(e) };
    }

    /// NULL arguments: each refused with nothing written.
    /// `mf_track_opaque_core`: levels below the shell (or a core of `−∞`); where the host is
    /// honest and no field varies, a query from `f >= start` that reaches `f <= core` (found by
    /// points along the ray, by a margin far above the rounding of their coordinates) has
    /// transmittance estimates of exactly 0 up to that point.
    pub fn opaque_core(&mut self, q: &mf_track_query) {
        let (m, s) = (self.medium.0 as *const mf_medium, self.surface.0 as *const mf_surface);
        let (mut start, mut core) = (0.0, 0.0);
        // SAFETY: live handles, valid out-pointers.
        assert_eq!(unsafe { mf_track_opaque_core(m, s, &mut start, &mut core) }, mf_status::MF_OK, "{}", check::last_error());
        assert!(start < 0.0 && start.is_finite() && (core < start || core == f64::NEG_INFINITY), "opaque core: start {start}, core {core}");
        if !(core.is_finite() && self.field.is_none() && self.host.honest() && self.host.deterministic()) {
            return;
        }
        let (o, d) = (dvec3(q.origin), dvec3(q.d));
        if !o.is_finite() || (d.length() - 1.0).abs() > 1e-6 || !self.eval(o).is_some_and(|p| p.f >= start) {
            return;
        }
        // The library tracks along d renormalised (found by fuzzing: d of length 1 + 1e-6 put
        // the point at t = 1e-3 a hair inside a flipped sphere of radius 1e-3, σ = 1e-50, while
        // the tracked ray ended on its surface). Below the core by 1e-9 of the coordinates: far
        // beyond where rounding puts the tracker's points.
        let d = d.normalize();
        let reach = q.t_max.min(4.0 * self.size);
        let deep = |f: f64, p: DVec3, t: f64| f <= core - 1e-9 * (p.abs().max_element() + t);
        let Some(t) = (1..=32).map(|i| reach * i as f64 / 32.0).find(|&t| self.eval(o + t * d).is_some_and(|p| deep(p.f, o + t * d, t))) else { return };
        for seed in 0..4 {
            let into = mf_track_query { t_max: t, seed: q.seed ^ seed, exit_level: 0.0, ..*q };
            if let Some(tr) = self.transmittance(&into) {
                assert_eq!(tr.transmittance, 0.0, "a ray from f >= {start} into the opaque core (f <= {core} at t = {t}): {into:?}");
            }
        }
    }

    /// `mf_track_depth_roulette` from the query's origin, down a depth and with a uniform drawn
    /// from its seed's bits: a survival of 0 or in `(0, 1]`; NaN levels and `u` outside `[0, 1)`
    /// refused with nothing written. A kept ray's transmittance with that survival is an
    /// estimate in `[0, 1 / survival]`; a free flight refuses a survival below 1.
    pub fn depth_roulette(&mut self, q: &mf_track_query) {
        let (m, s) = (self.medium.0 as *const mf_medium, self.surface.0 as *const mf_surface);
        let f_from = if dvec3(q.origin).is_finite() { self.eval(dvec3(q.origin)).map_or(0.0, |p| p.f) } else { 0.0 };
        let f_to = f_from - self.shell_top() * ((q.seed >> 8) & 63) as f64 / 8.0;
        let u = ((q.seed >> 16) & 0xffff) as f64 / 65536.0;
        let roulette = |from: f64, to: f64, u: f64| {
            let mut survival = -1.0;
            // SAFETY: live handles, a valid out-pointer.
            let status = unsafe { mf_track_depth_roulette(m, s, from, to, u, &mut survival) };
            (status, survival)
        };
        for (from, to, u) in [(f64::NAN, f_to, u), (f_from, f64::NAN, u), (f_from, f_to, 1.0), (f_from, f_to, -0.0 - 1e-300), (f_from, f_to, f64::NAN)] {
            let (status, survival) = roulette(from, to, u);
            assert!(status != mf_status::MF_OK && survival == -1.0, "roulette ({from}, {to}, {u}): {status:?}, wrote {survival}");
        }
        check::null_out(|o| unsafe { mf_track_depth_roulette(m, s, f_from, f_to, u, o) });
        let (status, survival) = roulette(f_from, f_to, u);
        assert_eq!(status, mf_status::MF_OK, "{}", check::last_error());
        assert!(survival == 0.0 || (survival > 0.0 && survival <= 1.0), "survival {survival}");
        if !(survival > 0.0 && survival < 1.0) {
            return;
        }
        let kept = mf_track_query { survival, ..*q };
        let (f, user_data) = (self.field_ptr(), self.host.user_data());
        assert!(check::call(|o| unsafe { mf_track_free_flight(m, s, f, user_data, &kept, o) }).is_err(), "a free flight took survival {survival}");
        if let Ok(t) = self.with_host("mf_track_transmittance", |u| check::call(|o| unsafe { mf_track_transmittance(m, s, f, u, &kept, o) })) {
            assert!(t.transmittance >= 0.0 && t.transmittance <= (1.0 + 1e-12) / survival, "survival {survival}: estimate {}", t.transmittance);
            check::ended(t.t, &kept);
            self.honest_stats(&t.stats);
        }
    }

    pub fn nulls(&mut self, q: &mf_track_query) {
        let (m, s, f) = (self.medium.0 as *const mf_medium, self.surface.0 as *const mf_surface, self.field_ptr());
        let u = self.host.user_data();
        check::null_out(|o| unsafe { mf_track_free_flight(m, s, f, u, q, o) });
        check::null_out(|o| unsafe { mf_track_transmittance(m, s, f, u, q, o) });
        check::null_out(|o| unsafe { mf_surface_eval(s, u, q.origin, o) });
        assert!(check::call(|o| unsafe { mf_track_free_flight(ptr::null(), s, f, u, q, o) }).is_err());
        assert!(check::call(|o| unsafe { mf_track_free_flight(m, ptr::null(), f, u, q, o) }).is_err());
        assert!(check::call(|o| unsafe { mf_track_transmittance(m, s, f, u, ptr::null(), o) }).is_err());
        assert!(check::call_array::<mf_collision>(1, |o| unsafe { mf_track_free_flight_batch(m, s, f, u, ptr::null(), 1, o) }).is_err());
        assert!(check::status(unsafe { mf_track_transmittance_batch(m, s, f, u, q, 1, ptr::null_mut()) }).is_err());
        assert!(check::status(unsafe { mf_surface_bounding_box(s, ptr::null_mut(), ptr::null_mut()) }).is_err());
        check::null_out(|o| unsafe { mf_surface_enclosure(s, u, 0.0, self.size, o) });
        unsafe {
            mf_surface_free(ptr::null_mut());
            mf_field_free(ptr::null_mut());
            mf_enclosure_free(ptr::null_mut());
        }
    }
}
