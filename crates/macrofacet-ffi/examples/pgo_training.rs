//! The training run of the profile-guided release build (`MF_PGO`, cmake/CargoBuild.cmake): what
//! a host's path tracer asks of the C ABI, per path, through the macrofacet media that cost the
//! most. It prints one line per medium and nothing else; its output is the profile the compiler
//! reads (LLVM's instrumentation: `-Cprofile-generate`), not a figure.
//!
//! Each path enters a shell at its enclosure (the offset of the surface by the exit level, as
//! mfrender's region boundaries), and at every collision does what mfrender's integrator does:
//! next-event estimation (the phase value toward a light direction, then a shadow ray's
//! transmittance to the exit, from the collision with its hint), a phase sample, and the escape
//! flight along it (to the exit, with the hint) — until a flight leaves the shell.
//!
//! The scenes are not the benchmarks' (bench/anchor.xml, bench/gpis_compare.xml): a sphere of
//! radius 2 and a torus mesh of 48 × 20 quads with vertex normals, each as thin, in-between and
//! volume-like shells of each distribution family, diffuse flakes and the mixture sampler; and
//! the realization-based reference (`mf_gpis_trace`, the crossings' reflections) around the
//! sphere, as mfrender's `gpis` medium calls it. What the training leaves out, the compiler
//! treats as cold: each kind of medium a host renders should have its share.
//! Usage: `cargo run --release -p macrofacet-ffi --example pgo_training [paths]` (default 6,000
//! per medium; a tenth of that for the realizations, each ~50 times as costly).

#[path = "../tests/common/mod.rs"]
mod common;

use glam::DVec3;
use macrofacet::rng::Pcg32;
use macrofacet_ffi::*;
use std::ffi::{c_void, CString};
use std::ptr;

fn check(status: mf_status, what: &str) {
    if status != mf_status::MF_OK {
        panic!("pgo_training: {what}: {}", common::last_error());
    }
}

/// The training's random numbers (and the tracking calls' seeds): the library's own generator.
struct Rng(Pcg32);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        (u64::from(self.0.next_u32()) << 32) | u64::from(self.0.next_u32())
    }

    fn next_f64(&mut self) -> f64 {
        self.0.next_f64()
    }

    /// A uniform direction.
    fn direction(&mut self) -> DVec3 {
        let (z, phi) = (1.0 - 2.0 * self.next_f64(), std::f64::consts::TAU * self.next_f64());
        let s = (1.0 - z * z).max(0.0).sqrt();
        DVec3::new(s * phi.cos(), s * phi.sin(), z)
    }

    /// A direction into a surface whose outward normal is `n`, spread about `−n`.
    fn inward(&mut self, n: DVec3) -> DVec3 {
        let d = (-n + 0.9 * self.direction()).normalize_or(-n);
        if d.dot(n) < 0.0 {
            d
        } else {
            -d
        }
    }
}

/// A parameter's value (`mf_params_set_float` or `_string`).
#[derive(Clone, Copy)]
enum Value {
    Float(f64),
    Text(&'static str),
}

/// A shell of the training: its label, its share of the paths (in tenths) and its parameters.
type Shell = (&'static str, u32, Vec<(&'static str, Value)>);

/// The parameters of a medium (for `mf_medium_new` and `mf_gpis_new` alike).
fn params(named: &[(&str, Value)]) -> *mut mf_params {
    let mut params = ptr::null_mut();
    // SAFETY: valid pointers and NUL-terminated strings throughout.
    unsafe {
        check(mf_params_new(&mut params), "mf_params_new");
        for &(name, value) in named {
            let name = CString::new(name).unwrap();
            match value {
                Value::Float(x) => check(mf_params_set_float(params, name.as_ptr(), x), "mf_params_set_float"),
                Value::Text(text) => {
                    let text = CString::new(text).unwrap();
                    check(mf_params_set_string(params, name.as_ptr(), text.as_ptr()), "mf_params_set_string");
                }
            }
        }
    }
    params
}

fn medium(named: &[(&str, Value)]) -> *mut mf_medium {
    let (params, mut medium) = (params(named), ptr::null_mut());
    // SAFETY: a valid parameter set, freed once.
    unsafe {
        check(mf_medium_new(params, &mut medium), "mf_medium_new");
        mf_params_free(params);
    }
    medium
}

/// The mean surface's signed distance for `mf_gpis_trace`: `user_data` is the `mf_surface`.
unsafe extern "C" fn mean_sdf(user_data: *mut c_void, p: mf_vec3, out: *mut mf_sdf_sample) {
    // SAFETY: all-zero is a valid mf_surface_point; the handle and `out` are valid (the caller's).
    unsafe {
        let mut point: mf_surface_point = std::mem::zeroed();
        let ok = mf_surface_eval(user_data as *const mf_surface, ptr::null_mut(), p, &mut point) == mf_status::MF_OK;
        *out = mf_sdf_sample { f: if ok { point.f } else { f64::NAN }, gradient: point.normal, u: point.u, v: point.v };
    }
}

/// Paths through realizations of a GPIS around the sphere of radius 2 (`surface`): from outside
/// its envelope toward it, each crossing reflected (`mf_gpis_scatter`) and traced on from there,
/// as far as the ball that holds the envelope. Returns the crossings, to print.
fn train_gpis(gpis: *const mf_gpis, surface: *mut mf_surface, paths: u32, rng: &mut Rng) -> u64 {
    let mut envelope = 0.0;
    // SAFETY: valid handle and out pointer.
    unsafe { check(mf_gpis_envelope(gpis, ptr::null(), &mut envelope), "mf_gpis_envelope") };
    let reach = 2.0 + envelope;
    // The distance from `o` (inside the ball) along `d` to the ball's boundary.
    let exit = |o: DVec3, d: DVec3| {
        let b = o.dot(d);
        -b + (b * b - (o.length_squared() - reach * reach)).max(0.0).sqrt()
    };
    let mut crossings = 0;
    for _ in 0..paths {
        let n = rng.direction();
        let (mut origin, mut d) = (n * reach * (1.0 - 1e-9), rng.inward(n));
        let mut start = mf_gpis_start { kind: MF_GPIS_START_FREE, gradient: DVec3::ZERO.into() };
        for _depth in 0..8 {
            // SAFETY: all-zero is a valid mf_gpis_hit; valid handles, callback and pointers.
            let mut hit: mf_gpis_hit = unsafe { std::mem::zeroed() };
            unsafe { check(mf_gpis_trace(gpis, Some(mean_sdf), ptr::null(), surface.cast(), origin.into(), d.into(), exit(origin, d), &start, rng.next_u64(), &mut hit), "mf_gpis_trace") };
            if !hit.hit {
                break;
            }
            crossings += 1;
            let local: *const mf_local_params = if hit.local.set == 0 { ptr::null() } else { &hit.local };
            // SAFETY: as above.
            let mut sample: mf_phase_sample_result = unsafe { std::mem::zeroed() };
            unsafe { check(mf_gpis_scatter(gpis, local, (-d).into(), hit.normal, &mut sample), "mf_gpis_scatter") };
            if !sample.valid {
                break;
            }
            (origin, d) = (DVec3::from(hit.point), DVec3::from(sample.wo));
            start = mf_gpis_start { kind: MF_GPIS_START_ON_SURFACE, gradient: hit.gradient };
        }
    }
    crossings
}

/// A torus of `u × v` quads (major radius `big`, minor `small`) about `z`, with its vertex
/// normals: positions, triangle indices, normals. (The validation crate's `meshes::torus` in the
/// C ABI's flat arrays; that crate is not a dependency here: its plotting would lengthen every
/// profile-guided build.)
fn torus(big: f64, small: f64, u: u32, v: u32) -> (Vec<f64>, Vec<u32>, Vec<f64>) {
    let (mut positions, mut normals, mut indices) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..u {
        let a = std::f64::consts::TAU * f64::from(i) / f64::from(u);
        for j in 0..v {
            let b = std::f64::consts::TAU * f64::from(j) / f64::from(v);
            let n = DVec3::new(a.cos() * b.cos(), a.sin() * b.cos(), b.sin());
            let p = DVec3::new(big * a.cos(), big * a.sin(), 0.0) + small * n;
            positions.extend_from_slice(&[p.x, p.y, p.z]);
            normals.extend_from_slice(&[n.x, n.y, n.z]);
        }
    }
    let at = |i: u32, j: u32| (i % u) * v + (j % v);
    for i in 0..u {
        for j in 0..v {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            indices.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    (positions, indices, normals)
}

/// A point on the surface's enclosure and a direction into the shell: an entering ray.
type Entry<'a> = dyn Fn(&mut Rng) -> (DVec3, DVec3) + 'a;

/// One medium around one surface: `paths` paths entering at `entry`, with the tracking calls'
/// exit level `exit_level`. Returns the collisions, to print.
fn train(medium: *const mf_medium, surface: *const mf_surface, exit_level: f64, entry: &Entry<'_>, paths: u32, rng: &mut Rng) -> u64 {
    let mut collisions = 0;
    for _ in 0..paths {
        let (mut origin, mut d) = entry(rng);
        let mut hint = 0;
        for _depth in 0..16 {
            let query = mf_track_query { origin: origin.into(), d: d.into(), t_max: f64::INFINITY, seed: rng.next_u64(), exit_level, survival: 0.0, hint };
            // SAFETY: all-zero is a valid mf_collision (its bool is false).
            let mut c: mf_collision = unsafe { std::mem::zeroed() };
            // SAFETY: valid handles and pointers; a built-in surface takes no user data.
            unsafe { check(mf_track_free_flight(medium, surface, ptr::null(), ptr::null_mut(), &query, &mut c), "mf_track_free_flight") };
            if !c.scattered {
                break;
            }
            collisions += 1;
            let p = DVec3::from(c.p);
            let wi = -d;
            // Next-event estimation toward a uniform direction: the phase value, then the shadow
            // ray's transmittance where it is not zero.
            let light = rng.direction();
            // The collision's local parameters, NULL where the medium's own (as a host passes them).
            let local: *const mf_local_params = if c.local.set == 0 { ptr::null() } else { &c.local };
            // SAFETY: as above, for every call of the collision.
            unsafe {
                let mut value: mf_phase_value = std::mem::zeroed();
                check(mf_phase_eval_pdf_local(medium, local, &c.frame, wi.into(), light.into(), &mut value), "mf_phase_eval_pdf_local");
                if value.value.r > 0.0 || value.value.g > 0.0 || value.value.b > 0.0 {
                    let shadow = mf_track_query { origin: c.p, d: light.into(), t_max: f64::INFINITY, seed: rng.next_u64(), exit_level, survival: 0.0, hint: c.hint };
                    let mut t: mf_transmittance = std::mem::zeroed();
                    check(mf_track_transmittance(medium, surface, ptr::null(), ptr::null_mut(), &shadow, &mut t), "mf_track_transmittance");
                }
                let u: [f64; MF_PHASE_SAMPLE_DIMENSIONS] = std::array::from_fn(|_| rng.next_f64());
                let mut sample: mf_phase_sample_result = std::mem::zeroed();
                check(mf_phase_sample_local(medium, local, &c.frame, wi.into(), u.as_ptr(), &mut sample), "mf_phase_sample_local");
                if !sample.valid {
                    break;
                }
                (origin, d, hint) = (p, DVec3::from(sample.wo), c.hint);
            }
        }
    }
    collisions
}

fn main() {
    let paths: u32 = std::env::args().nth(1).map_or(6_000, |a| a.parse().expect("paths: a count"));
    let mut rng = Rng(Pcg32::new(0x7067_6f5f_7472_6169, 1));
    use Value::{Float, Text};
    let gold = ("material", Text("Au"));
    // The shells, each with its share of the paths: conductor flakes of each distribution family
    // (the thin and in-between ones most: they are what renders cost most), then diffuse flakes
    // and the mixture sampler.
    let media: [Shell; 7] = [
        ("thin beckmann", 10, vec![("sigma", Float(2e-3)), ("distribution", Text("beckmann")), ("alpha", Float(0.3)), gold]),
        ("in-between ggx", 10, vec![("sigma", Float(0.03)), ("distribution", Text("ggx")), ("alpha", Float(0.4)), gold]),
        ("volume-like beckmann", 10, vec![("sigma", Float(0.08)), ("distribution", Text("beckmann")), ("alpha", Float(0.8)), gold]),
        ("in-between anisotropic gpss", 5, vec![("sigma", Float(0.03)), ("distribution", Text("gpss")), ("alpha_u", Float(0.3)), ("alpha_v", Float(0.6)), ("alpha_z", Float(0.2)), gold]),
        ("thin gtr", 3, vec![("sigma", Float(2e-3)), ("distribution", Text("gtr")), ("gamma", Float(1.5)), ("alpha", Float(0.3)), gold]),
        ("thin diffuse flakes", 2, vec![("sigma", Float(2e-3)), ("distribution", Text("beckmann")), ("alpha", Float(0.5)), ("micro_bsdf", Text("diffuse"))]),
        ("in-between mixture", 3, vec![("sigma", Float(0.03)), ("distribution", Text("gpss")), ("alpha", Float(0.6)), ("vndf_sampling", Text("mixture")), gold]),
    ];

    // A sphere of radius 2 at the origin; its region reaches the exit level.
    let mut sphere = ptr::null_mut();
    // SAFETY: valid out pointer.
    unsafe { check(mf_surface_new_sphere(DVec3::ZERO.into(), 2.0, false, DVec3::Z.into(), &mut sphere), "mf_surface_new_sphere") };
    // A torus mesh with vertex normals, and its own enclosure's exit level per medium.
    let (positions, indices, normals) = torus(1.2, 0.5, 48, 20);
    let mesh = mf_mesh { positions: positions.as_ptr(), vertex_count: positions.len() / 3, indices: indices.as_ptr(), triangle_count: indices.len() / 3, normals: normals.as_ptr(), uvs: ptr::null() };
    let mut torus_surface = ptr::null_mut();
    // SAFETY: the arrays outlive the call, which copies them.
    unsafe { check(mf_surface_new_mesh(&mesh, 1, f64::INFINITY, &mut torus_surface), "mf_surface_new_mesh") };

    for (label, tenths, named) in &media {
        let m = medium(named);
        let paths = paths * tenths / 10;
        let mut top = 0.0;
        // SAFETY: valid handle and out pointer.
        unsafe { check(mf_medium_shell_top(m, &mut top), "mf_medium_shell_top") };

        // The sphere: rays from just inside the exit level, into the shell.
        let exit_level = top * (1.0 + 1e-3);
        let sphere_entry = move |rng: &mut Rng| {
            let n = rng.direction();
            (n * (2.0 + top * (1.0 + 5e-4)), rng.inward(n))
        };
        let on_sphere = train(m, sphere, exit_level, &sphere_entry, paths, &mut rng);

        // The torus: rays from its enclosure's exit level above a random point of a random
        // triangle, into the shell.
        let mut enclosure = ptr::null_mut();
        let mut torus_exit = 0.0;
        // SAFETY: valid handles and out pointers.
        unsafe {
            check(mf_surface_enclosure(torus_surface, ptr::null_mut(), top, 0.0, &mut enclosure), "mf_surface_enclosure");
            check(mf_enclosure_exit_level(enclosure, &mut torus_exit), "mf_enclosure_exit_level");
            mf_enclosure_free(enclosure);
        }
        let corner = |k: u32| DVec3::new(positions[3 * k as usize], positions[3 * k as usize + 1], positions[3 * k as usize + 2]);
        let torus_entry = |rng: &mut Rng| {
            let t = ((rng.next_f64() * (indices.len() / 3) as f64) as usize).min(indices.len() / 3 - 1);
            let [a, b, c] = [0, 1, 2].map(|k| corner(indices[3 * t + k]));
            let (mut s, mut r) = (rng.next_f64(), rng.next_f64());
            if s + r > 1.0 {
                (s, r) = (1.0 - s, 1.0 - r);
            }
            let n = (b - a).cross(c - a).normalize();
            (a + s * (b - a) + r * (c - a) + n * (top * (1.0 + 5e-4)), rng.inward(n))
        };
        let on_torus = train(m, torus_surface, torus_exit, &torus_entry, paths, &mut rng);
        println!("{label}: {on_sphere} collisions on the sphere, {on_torus} on the torus");
        // SAFETY: a handle made above, freed once.
        unsafe { mf_medium_free(m) };
    }
    // The realization-based reference around the sphere: the in-between GPSS of the paper's
    // Figs. 17/18 (σ = 0.02 of the radius), and a rougher, wider one.
    for (sigma, alpha) in [(0.04, 0.4), (0.1, 1.0)] {
        let (params, mut gpis) = (params(&[("sigma", Float(sigma)), ("distribution", Text("gpss")), ("alpha", Float(alpha)), gold]), ptr::null_mut());
        // SAFETY: a valid parameter set, freed once.
        unsafe {
            check(mf_gpis_new(params, &mut gpis), "mf_gpis_new");
            mf_params_free(params);
        }
        let crossings = train_gpis(gpis, sphere, paths / 10, &mut rng);
        println!("gpis (sigma {sigma}, gpss alpha {alpha}): {crossings} crossings on the sphere");
        // SAFETY: a handle made above, freed once.
        unsafe { mf_gpis_free(gpis) };
    }

    // SAFETY: handles made above, freed once.
    unsafe {
        mf_surface_free(sphere);
        mf_surface_free(torus_surface);
    }
}
