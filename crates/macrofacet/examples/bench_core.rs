//! Throughput of the core queries a renderer calls per event. Prints nanoseconds per call.
//!
//!     cargo run --release --example bench_core
//!     cargo run --release --example bench_core fields   (gpis vs macrofacet, varying parameters)
//!
//! Inputs are drawn once, before timing, from a fixed seed; each figure is the best of five
//! passes over the same inputs (to discount start-up noise on a shared machine).

use glam::DVec3;
use macrofacet::ndf::{Beckmann, Ggx, Gpss, Gtr, GtrLambda, Ltmd, LtmdBase, MicrofacetDistribution, Ndf};
use macrofacet::rng::Pcg32;
use macrofacet::{medium_from_params, ParamSet, PHASE_SAMPLE_DIMENSIONS};
use std::hint::black_box;
use std::time::Instant;

const N: usize = 200_000;

fn time(label: &str, mut body: impl FnMut(usize) -> f64) {
    let mut best = f64::INFINITY;
    let mut sink = 0.0;
    for _ in 0..5 {
        let start = Instant::now();
        for i in 0..N {
            sink += body(i);
        }
        best = best.min(start.elapsed().as_secs_f64());
    }
    black_box(sink);
    println!("{label:<44} {:>9.1} ns/call", best / N as f64 * 1e9);
}

fn uniform_direction(rng: &mut Pcg32) -> DVec3 {
    let z = 2.0 * rng.next_f64() - 1.0;
    let phi = 2.0 * std::f64::consts::PI * rng.next_f64();
    let r = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

fn main() {
    // `bench_core tracking [label filter]`: the tracking figures only (e.g. for a profiler).
    let args: Vec<String> = std::env::args().collect();
    if args.get(1).map(String::as_str) == Some("tracking") {
        tracking_benchmarks(args.get(2).map(String::as_str).unwrap_or(""));
        return;
    }
    if args.get(1).map(String::as_str) == Some("fields") {
        field_benchmarks();
        return;
    }
    let mut rng = Pcg32::new(1, 1);
    let dirs: Vec<DVec3> = (0..N).map(|_| uniform_direction(&mut rng)).collect();
    let us: Vec<[f64; PHASE_SAMPLE_DIMENSIONS]> = (0..N).map(|_| std::array::from_fn(|_| rng.next_f64())).collect();
    let fs: Vec<f64> = (0..N).map(|_| 6.0 * rng.next_f64() - 4.0).collect();

    let ndfs = [
        ("beckmann", Ndf::Beckmann(Beckmann::new(0.3, 0.5).unwrap())),
        ("ggx", Ndf::Ggx(Ggx::new(0.3, 0.5).unwrap())),
        ("gpss", Ndf::Gpss(Gpss::new(0.5, 0.5, 0.5).unwrap())),
        ("gtr γ=1.7", Ndf::Gtr(Gtr::new(0.3, 1.7, GtrLambda::Exact).unwrap())),
        ("gtr γ=1.7 dimov Λ", Ndf::Gtr(Gtr::new(0.3, 1.7, GtrLambda::Dimov).unwrap())),
        ("gtr γ=3", Ndf::Gtr(Gtr::new(0.3, 3.0, GtrLambda::Exact).unwrap())),
        ("gtr γ=1.7 skewed (ltmd)", Ndf::Ltmd(Ltmd::new(LtmdBase::Gtr(Gtr::new(0.3, 1.7, GtrLambda::Exact).unwrap()),
            glam::DMat2::from_cols(glam::DVec2::new(1.0, 0.0), glam::DVec2::new(2.0, 1.0))).unwrap())),
        ("ggx stretched (ltmd)", Ndf::Ltmd(Ltmd::stretch(LtmdBase::Ggx(Ggx::new(0.3, 0.3).unwrap()), 0.5).unwrap())),
    ];
    time("construction: gtr γ=1.7 (Gauss–Jacobi nodes)", |i| Gtr::new(0.3, 1.5 + 0.4 * us[i][0], GtrLambda::Exact).unwrap().alpha);
    for (name, ndf) in ndfs {
        time(&format!("{name}: D(m)"), |i| ndf.d(dirs[i]));
        time(&format!("{name}: projected_area(w)"), |i| ndf.projected_area(dirs[i]));
        time(&format!("{name}: sample_visible"), |i| {
            ndf.sample_visible(dirs[i], [us[i][0], us[i][1], us[i][2]]).map_or(0.0, |m| m.z)
        });
    }

    let mut p = ParamSet::new();
    p.set_float("sigma", 1.0).set_float("alpha", 0.5).set_string("material", "Au");
    let medium = medium_from_params(&p).unwrap();
    time("gpss medium: sigma_t(f, d)", |i| medium.sigma_t(fs[i], dirs[i]));
    time("gpss medium: transmittance(f, d, t)", |i| medium.transmittance(fs[i], dirs[i], 2.0));
    time("gpss medium: sample_free_flight(f, d, inf, u)", |i| {
        match medium.sample_free_flight(fs[i], dirs[i], f64::INFINITY, us[i][0]) {
            macrofacet::FreeFlight::Scatter { t } => t,
            macrofacet::FreeFlight::Pass => 0.0,
        }
    });
    time("gpss Au phase: eval(wi, wo)", |i| medium.phase.eval(dirs[i], dirs[(i + 1) % N])[0]);
    time("gpss Au phase: sample(wi, u)", |i| medium.phase.sample(dirs[i], us[i]).map_or(0.0, |s| s.pdf));

    let mut p = ParamSet::new();
    p.set_float("sigma", 1.0).set_float("alpha", 0.3).set_float("gamma", 1.7).set_string("distribution", "gtr").set_string("material", "Ag");
    let gtr = medium_from_params(&p).unwrap();
    time("gtr 1.7 medium: sample_free_flight", |i| match gtr.sample_free_flight(fs[i], dirs[i], f64::INFINITY, us[i][0]) {
        macrofacet::FreeFlight::Scatter { t } => t,
        macrofacet::FreeFlight::Pass => 0.0,
    });
    time("gtr 1.7 Ag phase: sample(wi, u)", |i| gtr.phase.sample(dirs[i], us[i]).map_or(0.0, |s| s.pdf));
    println!("size of an Ndf: {} bytes, of a medium: {} bytes", std::mem::size_of::<Ndf>(), std::mem::size_of::<macrofacet::MacrofacetMedium>());

    bench_closest();
    println!("\n== tracking (library tracker, per call)");
    tracking_benchmarks("");
}

/// Mesh generators shared with the integration tests.
use macrofacet_validation::common::meshes;

use macrofacet::surface::{MeanSurface, Sphere, TriangleMesh};
use macrofacet::tracking::{TrackStats, TrackedFlight, Tracker};

/// Rays as a renderer's region boundary hands them to the tracker: starting `gap` above the
/// shell's top over a random point of the surface, heading inward (cosine-weighted about the
/// normal); then a shadow ray from each collision in a random upper-hemisphere direction.
fn bench_tracking<S: MeanSurface>(label: &str, medium: &macrofacet::MacrofacetMedium, surface: &S, points: &[(DVec3, DVec3)], gap: f64) {
    let tracker = Tracker::new(medium, surface);
    let top = medium.height.top();
    let mut rng = Pcg32::new(9, 9);
    let rays: Vec<(DVec3, DVec3)> = points
        .iter()
        .map(|&(p, n)| {
            let (s, t) = n.any_orthonormal_pair();
            let (r, phi) = (rng.next_f64().sqrt(), 2.0 * std::f64::consts::PI * rng.next_f64());
            let d = -(n * (1.0 - r * r).max(0.0).sqrt() + s * (r * phi.cos()) + t * (r * phi.sin()));
            (p + n * (top + gap * rng.next_f64()), d)
        })
        .collect();
    let (mut flights, mut shadows) = (TrackStats::default(), TrackStats::default());
    let mut collisions = Vec::new();
    let start = Instant::now();
    for (i, &(o, d)) in rays.iter().enumerate() {
        if let TrackedFlight::Scatter { t, point, .. } = tracker.sample_free_flight(o, d, f64::INFINITY, &mut Pcg32::new(i as u64, 1), &mut flights).unwrap() {
            collisions.push((o + t * d, point.normal));
        }
    }
    let flight_time = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let mut sum = 0.0;
    for (i, &(p, n)) in collisions.iter().enumerate() {
        let mut d = uniform_direction(&mut rng);
        if d.dot(n) < 0.0 {
            d = -d;
        }
        sum += tracker.transmittance(p, d, f64::INFINITY, &mut Pcg32::new(i as u64, 2), &mut shadows).unwrap();
    }
    let shadow_time = start.elapsed().as_secs_f64();
    black_box(sum);
    let per = |s: &TrackStats, n: usize| (s.surface_queries as f64 / n as f64, s.segments as f64 / n as f64, s.tentative_collisions as f64 / n as f64);
    let (q, g, c) = per(&flights, rays.len());
    println!(
        "{label:<30} free flight {:>7.0} ns ({q:.2} queries, {g:.2} segments, {c:.2} tentative; {:.0} ns/segment, {:.0} ns/tentative), violations {}",
        flight_time / rays.len() as f64 * 1e9,
        flight_time / flights.segments.max(1) as f64 * 1e9,
        flight_time / flights.tentative_collisions.max(1) as f64 * 1e9,
        flights.majorant_violations
    );
    let (q, g, c) = per(&shadows, collisions.len().max(1));
    println!(
        "{:<30} shadow ray  {:>7.0} ns ({q:.2} queries, {g:.2} segments, {c:.2} tentative), violations {}",
        "",
        shadow_time / collisions.len().max(1) as f64 * 1e9,
        shadows.majorant_violations
    );
}

fn tracking_benchmarks(filter: &str) {
    const RAYS: usize = 20_000;
    let mut rng = Pcg32::new(3, 3);
    let medium = |sigma: f64, params: &[(&str, &str)]| {
        let mut p = ParamSet::new();
        p.set_float("sigma", sigma).set_string("material", "Au");
        for (name, value) in params {
            match value.parse::<f64>() {
                Ok(x) => p.set_float(name, x),
                Err(_) => p.set_string(name, value),
            };
        }
        medium_from_params(&p).unwrap()
    };
    // The anchor sphere: radius 1, sigma 1e-3, Beckmann 0.3.
    let sphere = Sphere::new(DVec3::ZERO, 1.0, false, DVec3::Z).unwrap();
    let points: Vec<(DVec3, DVec3)> = (0..RAYS).map(|_| {
        let n = uniform_direction(&mut rng);
        (n, n)
    }).collect();
    if "sphere, sigma 1e-3 (thin)".contains(filter) {
        bench_tracking("sphere, sigma 1e-3 (thin)", &medium(1e-3, &[("distribution", "beckmann"), ("alpha", "0.3")]), &sphere, &points, 0.0);
    }
    // The default scene's torus (64 x 24, R 0.5, r 0.2) at its three sigmas; rays start up to one
    // enclosure cell (1/128 of the extent, times sqrt 3) above the shell, as in mfrender.
    let t = meshes::torus(0.5, 0.2, 64, 24);
    let start = Instant::now();
    let torus = TriangleMesh::new(&t.positions, &t.indices, t.normals.as_deref(), None, 1, f64::INFINITY).unwrap();
    let built = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let boundary = macrofacet::surface::enclosure(&torus, 0.006, 0.0).unwrap();
    println!(
        "torus mesh ({} triangles): surface built in {:.1} ms, its shell's enclosure ({} triangles) in {:.1} ms",
        t.indices.len(),
        built * 1e3,
        boundary.triangles.len(),
        start.elapsed().as_secs_f64() * 1e3
    );
    let points: Vec<(DVec3, DVec3)> = (0..RAYS)
        .map(|_| {
            let (phi, theta) = (2.0 * std::f64::consts::PI * rng.next_f64(), 2.0 * std::f64::consts::PI * rng.next_f64());
            let n = DVec3::new(theta.cos() * phi.cos(), theta.cos() * phi.sin(), theta.sin());
            let p = DVec3::new(0.5 * phi.cos(), 0.5 * phi.sin(), 0.0) + 0.2 * n;
            let q = torus.point(p).unwrap();
            (p - q.f * q.normal, q.normal)
        })
        .collect();
    let gap = 1.4 / 128.0 * 3f64.sqrt();
    for (label, sigma, params) in [
        ("torus, sigma 0.002 (thin)", 0.002, vec![("alpha_u", "0.12"), ("alpha_v", "0.12"), ("alpha_z", "0")]),
        ("torus, sigma 0.02 (in-between)", 0.02, vec![("alpha_u", "0.4"), ("alpha_v", "0.4"), ("alpha_z", "0.2")]),
        ("torus, sigma 0.05 (volume-like)", 0.05, vec![("alpha", "1")]),
    ] {
        if label.contains(filter) {
            bench_tracking(label, &medium(sigma, &params), &torus, &points, gap);
        }
    }
}

#[allow(dead_code)]
fn bench_closest() {
    let t = meshes::torus(0.5, 0.2, 64, 24);
    let torus = TriangleMesh::new(&t.positions, &t.indices, t.normals.as_deref(), None, 1, f64::INFINITY).unwrap();
    let mut rng = Pcg32::new(4, 4);
    let pts: Vec<DVec3> = (0..N)
        .map(|_| {
            let (phi, theta) = (2.0 * std::f64::consts::PI * rng.next_f64(), 2.0 * std::f64::consts::PI * rng.next_f64());
            let n = DVec3::new(theta.cos() * phi.cos(), theta.cos() * phi.sin(), theta.sin());
            DVec3::new(0.5 * phi.cos(), 0.5 * phi.sin(), 0.0) + (0.2 + 0.01 * (rng.next_f64() - 0.5)) * n
        })
        .collect();
    time("torus mesh: point(p) near the surface", |i| torus.point(pts[i]).unwrap().f);
}

/// The planar GPSS and its `σ` ramp, shared with the integration tests.
use macrofacet_validation::common::planar;

use macrofacet::field::{Constant, MediumField};
use macrofacet_gpis::{mirror_random_walk, GpisTracer, GpisWalk, Memory, Plane, SeKernel};

/// A path in the macrofacet medium: tracked free flights and phase samples with the local
/// parameters of each collision, from `origin` along `−wi` until it leaves; its bounce count.
fn macrofacet_walk<F: MediumField>(tracker: &Tracker<planar::PlaneSurface, F>, medium: &macrofacet::MacrofacetMedium, origin: DVec3, wi: DVec3, rng: &mut Pcg32) -> u32 {
    let (mut o, mut d) = (origin, -wi);
    let mut stats = TrackStats::default();
    for bounces in 0..100 {
        match tracker.sample_free_flight(o, d, f64::INFINITY, rng, &mut stats).unwrap() {
            TrackedFlight::Pass => return bounces,
            TrackedFlight::Scatter { t, point, local, .. } => {
                let frame = macrofacet::frame::Frame::from_normal_tangent(point.normal, point.tangent).unwrap();
                let local_medium = medium.localized(&local, &frame).unwrap();
                let u: [f64; PHASE_SAMPLE_DIMENSIONS] = std::array::from_fn(|_| rng.next_f64());
                let Some(sample) = local_medium.phase.sample(frame.to_local(-d), u) else { return bounces };
                o += t * d;
                d = frame.to_world(sample.wo);
            }
        }
    }
    100
}

/// A Renewal+ mirror walk of the GPIS (seeded by the path's index); its bounce count.
fn gpis_walk<F: MediumField>(tracer: &GpisTracer<'_, Plane, F>, i: usize, origin: DVec3, wi: DVec3) -> u32 {
    let mut rng = Pcg32::new(i as u64, 5);
    match mirror_random_walk(tracer, origin, wi, Memory::RenewalPlus, 100, &mut || rng.next_f64()).unwrap() {
        GpisWalk::Escaped { bounces, .. } | GpisWalk::Lost { bounces } => bounces,
    }
}

/// Microseconds per path (best of three passes) and mean bounces of `walk` over `paths`.
fn time_paths(paths: &[(DVec3, DVec3)], mut walk: impl FnMut(usize, DVec3, DVec3) -> u32) -> (f64, f64) {
    let (mut best, mut bounces) = (f64::INFINITY, 0u64);
    for _ in 0..3 {
        bounces = 0;
        let start = Instant::now();
        for (i, &(o, wi)) in paths.iter().enumerate() {
            bounces += walk(i, o, wi) as u64;
        }
        best = best.min(start.elapsed().as_secs_f64());
    }
    (best / paths.len() as f64 * 1e6, bounces as f64 / paths.len() as f64)
}

/// Both methods' paths with `field`: microseconds per path, printed with their ratio.
fn time_field<F: MediumField>(label: &str, paths: &[(DVec3, DVec3)], kernel: SeKernel, medium: &macrofacet::MacrofacetMedium, field: &F) -> (f64, f64) {
    let plane = Plane::default();
    let (tracer, tracker) = (GpisTracer::with_field(&plane, kernel, field), Tracker::with_field(medium, &planar::PlaneSurface, field));
    let (g, gb) = time_paths(paths, |i, o, wi| gpis_walk(&tracer, i, o, wi));
    let (m, mb) = time_paths(paths, |i, o, wi| macrofacet_walk(&tracker, medium, o, wi, &mut Pcg32::new(i as u64, 6)));
    println!("{label:<34} gpis {g:>8.1} us/path ({gb:.3} bounces)   macrofacet {m:>6.2} us/path ({mb:.3} bounces)   gpis/macrofacet {:>6.1}x", g / m);
    (g, m)
}

/// gpis vs macrofacet on a varying-parameter case: mirror-flake paths into a planar GPSS whose
/// σ ramps from 0.5 to 1 across x ∈ [−2, 2] (α = 1, so the lengthscales follow σ), against the
/// same plane with σ = 1 everywhere. Both methods go through their field code path (the
/// macrofacet one through the library's tracker, the plane as its mean surface), one thread,
/// the same paths for all four runs.
fn field_benchmarks() {
    const PATHS: usize = 4000;
    let mut rng = Pcg32::new(12, 12);
    let paths: Vec<(DVec3, DVec3)> = (0..PATHS)
        .map(|_| {
            let phi = 2.0 * std::f64::consts::PI * rng.next_f64();
            let wi = DVec3::new(std::f64::consts::FRAC_1_SQRT_2 * phi.cos(), std::f64::consts::FRAC_1_SQRT_2 * phi.sin(), std::f64::consts::FRAC_1_SQRT_2);
            (DVec3::new(8.0 * rng.next_f64() - 4.0, 0.0, 6.0) + 6.0 * wi, wi)
        })
        .collect();
    let kernel = SeKernel::from_roughness(1.0, DVec3::ONE).unwrap();
    let mut p = ParamSet::new();
    p.set_float("sigma", 1.0).set_float("alpha", 1.0).set_float("shell_extent", 6.0).set_string("material", "none");
    let medium = medium_from_params(&p).unwrap();
    let ramp = planar::SigmaAcross { sigma: [0.5, 1.0], width: 4.0 };
    println!("== gpis vs macrofacet, planar GPSS (isotropic, alpha 1, mirror flakes), {PATHS} paths from 45 deg at x in [-4, 4], 1 thread");
    println!("   (gpis: Renewal+ realizations, seeds/004; macrofacet: the library's tracker + phase sampling)");
    let (gs, ms) = time_field("stationary (sigma 1)", &paths, kernel, &medium, &Constant);
    // The field machinery alone: σ = 1 everywhere, but through a field.
    let (gf, mf) = time_field("sigma 1 through a field", &paths, kernel, &medium, &planar::SigmaAcross { sigma: [1.0, 1.0], width: 0.0 });
    let (gv, mv) = time_field("varying (sigma ramp 0.5 -> 1)", &paths, kernel, &medium, &ramp);
    println!("cost over stationary: the field path gpis {:.2}x, macrofacet {:.2}x; the ramp gpis {:.2}x, macrofacet {:.2}x", gf / gs, mf / ms, gv / gs, mv / ms);
    println!("(the ramp's gpis cost grows with its samples: the band is 6 sigma_max thick and the steps follow the local lengthscale)");
}
