//! The tracker around curved mean surfaces (issue "the library owns the volume event"):
//! free-flight distances against the exact distribution from quadrature of `σ_t` along the ray
//! (Kolmogorov–Smirnov) and against a brute-force delta tracker with a loose constant majorant
//! (two-sample KS), transmittance estimates against the exact transmittance, and no majorant
//! violation on spheres of radius 10σ, sharp-edged and non-convex meshes, and a smooth torus.

use macrofacet_validation::common;

use common::meshes::{self, Mesh};
use glam::{DVec2, DVec3};
use macrofacet::field::{Constant, LocalParams, MediumField, ParamBounds};
use macrofacet::height::HeightProfile;
use macrofacet::ndf::{Beckmann, Gpss, MicrofacetDistribution, Ndf};
use macrofacet::rng::Pcg32;
use macrofacet::special::normal_cdf;
use macrofacet_validation::stats::{kolmogorov_sf, ks_test, mean_and_standard_error, sidak_alpha};
use macrofacet::surface::{MeanSurface, Sphere, TriangleMesh};
use macrofacet::tracking::{TrackStats, TrackedFlight, Tracker};
use macrofacet::{MacrofacetMedium, MacrofacetPhase, MicroBsdf, VndfSampling};

fn medium(ndf: Ndf, sigma: f64) -> MacrofacetMedium {
    MacrofacetMedium {
        height: HeightProfile::new(sigma, 3.0).unwrap(),
        phase: MacrofacetPhase { ndf, micro_bsdf: MicroBsdf::Mirror { specular_reflectance: [1.0; 3] }, sampling: VndfSampling::Exact },
    }
}

fn mesh_surface(m: &Mesh) -> TriangleMesh {
    mesh_surface_within(m, f64::INFINITY)
}

/// The surface built for media tracked up to `reach` from it (its closed forms stop a few reaches
/// out).
fn mesh_surface_within(m: &Mesh, reach: f64) -> TriangleMesh {
    TriangleMesh::new(&m.positions, &m.indices, m.normals.as_deref(), None::<&[DVec2]>, 1, reach).unwrap()
}

/// `τ(t)` along a ray by Gauss–Legendre panels of `σ/20`, tabulated at the panel edges up to
/// `t_max` or until `τ > 60`.
struct OpticalDepth {
    h: f64,
    tau: Vec<f64>,
}

impl OpticalDepth {
    fn new<S: MeanSurface, F: MediumField>(tracker: &Tracker<S, F>, surface: &S, sigma: f64, o: DVec3, d: DVec3, t_max: f64) -> Self {
        let h = sigma / 20.0;
        let nodes = common::gauss_legendre(4);
        let mut tau = vec![0.0];
        let mut t = 0.0;
        while t < t_max && *tau.last().unwrap() < 60.0 {
            let mut panel = 0.0;
            for &(x, w) in &nodes {
                let s = t + 0.5 * h * (1.0 + x);
                let p = o + s * d;
                panel += 0.5 * h * w * tracker.sigma_t_at(p, &surface.point(p).unwrap(), d).unwrap().0;
            }
            tau.push(tau.last().unwrap() + panel);
            t += h;
        }
        OpticalDepth { h, tau }
    }

    fn at(&self, t: f64) -> f64 {
        let x = t / self.h;
        let i = x.floor() as usize;
        if i + 1 >= self.tau.len() {
            return *self.tau.last().unwrap() * if self.tau.last().unwrap() >= &60.0 { f64::INFINITY } else { 1.0 };
        }
        let f = x - i as f64;
        self.tau[i] * (1.0 - f) + self.tau[i + 1] * f
    }
}

/// A brute-force free flight: delta tracking with constant majorants over segments of length
/// `max(σ, |f|/2)` from the Lipschitz bound `f >= f(t) − Δ`, times the largest projected area
/// over a 1° grid of directions (×1.1) — loose, simple, sharing nothing with the tracker's bounds.
// Eight plain inputs of one test helper (the tracker's and the ray's); a struct would only rename them.
#[allow(clippy::too_many_arguments)]
fn brute_force_flight<S: MeanSurface>(tracker: &Tracker<S>, surface: &S, m: &MacrofacetMedium, s_max: f64, o: DVec3, d: DVec3, t_max: f64, rng: &mut Pcg32) -> Option<f64> {
    let (sigma, top) = (m.height.sigma, m.height.top());
    let mut t = 0.0;
    while t < t_max {
        let f0 = surface.point(o + t * d).unwrap().f;
        if f0 > top + sigma {
            t += f0 - top;
            continue;
        }
        let len = sigma.max(0.5 * f0.abs()).min(t_max - t);
        let mu = s_max * m.height.density(f0 - len);
        let end = t + len;
        loop {
            t += -rng.next_f64_open().ln() / mu;
            if t >= end {
                t = end;
                break;
            }
            let st = tracker.sigma_t(&surface.point(o + t * d).unwrap(), d);
            assert!(st <= mu, "brute-force majorant exceeded");
            if rng.next_f64() * mu < st {
                return Some(t);
            }
        }
    }
    None
}

fn largest_projected_area(ndf: &Ndf) -> f64 {
    let mut s_max: f64 = 0.0;
    for i in 0..=180 {
        for j in 0..360 {
            let (th, ph) = ((i as f64).to_radians(), (j as f64).to_radians());
            s_max = s_max.max(ndf.projected_area(DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos())));
        }
    }
    1.1 * s_max
}

/// Two-sample Kolmogorov–Smirnov p-value.
fn ks_two_sample(a: &mut [f64], b: &mut [f64]) -> f64 {
    a.sort_by(f64::total_cmp);
    b.sort_by(f64::total_cmp);
    let (n, m) = (a.len() as f64, b.len() as f64);
    let (mut i, mut j, mut d) = (0, 0, 0.0f64);
    while i < a.len() && j < b.len() {
        let x = a[i].min(b[j]);
        while i < a.len() && a[i] <= x {
            i += 1;
        }
        while j < b.len() && b[j] <= x {
            j += 1;
        }
        d = d.max((i as f64 / n - j as f64 / m).abs());
    }
    let ne = (n * m / (n + m)).sqrt();
    kolmogorov_sf((ne + 0.12 + 0.11 / ne) * d)
}

struct Case {
    name: &'static str,
    origin: DVec3,
    d: DVec3,
    t_max: f64,
}

fn ray(name: &'static str, origin: DVec3, toward: DVec3, t_max: f64) -> Case {
    Case { name, origin, d: (toward - origin).normalize(), t_max }
}

/// Checks one surface: per ray, free flights (KS vs exact, pass fraction) and transmittance
/// (mean vs exact); returns the number of statistical comparisons failed and the stats.
fn check_surface<S: MeanSurface>(label: &str, m: &MacrofacetMedium, surface: &S, cases: &[Case], n: usize, alpha: f64, seed: u64) -> (usize, TrackStats) {
    check_field(label, m, surface, &Constant, m.height.sigma, cases, n, alpha, seed)
}

/// [`check_surface`] for a medium whose parameters `field` gives (quadrature panels of
/// `sigma_min / 20`).
#[allow(clippy::too_many_arguments)]
fn check_field<S: MeanSurface, F: MediumField>(label: &str, m: &MacrofacetMedium, surface: &S, field: &F, sigma_min: f64, cases: &[Case], n: usize, alpha: f64, seed: u64) -> (usize, TrackStats) {
    let tracker = Tracker::with_field(m, surface, field);
    let mut failures = 0;
    let mut total = TrackStats::default();
    for (k, case) in cases.iter().enumerate() {
        let tau = OpticalDepth::new(&tracker, surface, sigma_min, case.origin, case.d, case.t_max);
        let tau_max = tau.at(case.t_max);
        let p_pass = (-tau_max).exp();
        let mut rng = Pcg32::new(seed, k as u64);
        let mut stats = TrackStats::default();
        let mut distances = Vec::new();
        for _ in 0..n {
            let mut one = TrackStats::default();
            let seed = rng.next_u32() as u64 | (rng.next_u32() as u64) << 32;
            match tracker.sample_free_flight(case.origin, case.d, case.t_max, &mut Pcg32::new(seed, 1), &mut one).unwrap() {
                TrackedFlight::Scatter { t, point, .. } => {
                    assert!(t >= 0.0 && t <= case.t_max, "{label}/{}: t = {t} outside [0, {}]", case.name, case.t_max);
                    assert!((point.f - surface.point(case.origin + t * case.d).unwrap().f).abs() < 1e-9);
                    distances.push(t);
                }
                TrackedFlight::Pass => {}
            }
            stats.add(&one);
        }
        // Free flights: scattered distances vs the exact conditional CDF, pass count vs exp(-τ).
        let scattered = distances.len();
        let ks = if scattered > 0 && p_pass < 1.0 {
            ks_test(&mut distances, |t| (-(-tau.at(t)).exp_m1()) / (-(-tau_max).exp_m1())).p_value
        } else {
            1.0
        };
        let var = p_pass * (1.0 - p_pass) / n as f64;
        let z_pass = if var > 0.0 { ((n - scattered) as f64 / n as f64 - p_pass) / var.sqrt() } else { 0.0 };
        let p_binomial = 2.0 * normal_cdf(-z_pass.abs());
        // Transmittance: the mean of the estimates vs exp(-τ).
        let estimates: Vec<f64> = (0..n)
            .map(|i| {
                let mut one = TrackStats::default();
                let t = tracker.transmittance(case.origin, case.d, case.t_max, &mut Pcg32::new(seed ^ 0x5eed, (k * n + i) as u64), &mut one).unwrap();
                assert!((0.0..=1.0).contains(&t));
                stats.add(&one);
                t
            })
            .collect();
        let (mean, se) = mean_and_standard_error(estimates.iter().copied());
        // Rare non-zero estimates (Russian roulette) can leave every sample at 0: the variance of
        // an estimator in [0, 1] is at most its mean, which floors the standard error.
        let se = se.max((p_pass.max(mean) / n as f64).sqrt().min(1.0) * 0.0 + 0.0).max(if mean == 0.0 { (p_pass / n as f64).sqrt() } else { 0.0 });
        // The quadrature's own error (panels of σ/20 across the jump of ρ at the top face).
        let z_t = (mean - p_pass) / (se + 1e-3 * p_pass.max(1e-3));
        let p_t = 2.0 * normal_cdf(-z_t.abs());
        let ok = ks > alpha && p_binomial > alpha && p_t > alpha;
        println!(
            "{label}/{}: P(pass) exact {p_pass:.5}, KS p {ks:.3}, pass z {z_pass:+.2}; T mean {mean:.5} ± {se:.5} (z {z_t:+.2}); per flight+T: {:.2} queries, {:.2} segments, {:.2} tentative; violations {}",
            case.name,
            stats.surface_queries as f64 / (2 * n) as f64,
            stats.segments as f64 / (2 * n) as f64,
            stats.tentative_collisions as f64 / (2 * n) as f64,
            stats.majorant_violations
        );
        if !ok {
            failures += 1;
            println!("  FAILED at alpha {alpha:.2e}");
        }
        total.add(&stats);
    }
    (failures, total)
}

fn sphere_cases(r: f64, sigma: f64) -> Vec<Case> {
    let top = r + 3.0 * sigma;
    let far = 4.0 * r;
    vec![
        ray("normal", DVec3::new(-far, 0.0, 0.0), DVec3::ZERO, 8.0 * r),
        ray("oblique", DVec3::new(-far, 0.6 * r, 0.1 * r), DVec3::new(0.0, 0.6 * r, 0.1 * r), 8.0 * r),
        ray("grazing_shell", DVec3::new(-far, 0.0, r + sigma), DVec3::new(0.0, 0.0, r + sigma), 8.0 * r),
        ray("grazing_top", DVec3::new(-far, 0.0, top - 0.3 * sigma), DVec3::new(0.0, 0.0, top - 0.3 * sigma), 8.0 * r),
        ray("leaving", DVec3::new(0.0, 0.0, r - 0.5 * sigma), DVec3::new(1.0, 0.0, r + 0.3), 3.0 * r),
        ray("short_inside", DVec3::new(0.0, 0.0, r + 0.5 * sigma), DVec3::new(0.2 * r, 0.0, r - sigma), 0.2 * r),
    ]
}

#[test]
fn sphere_of_radius_ten_sigma() {
    let (r, sigma) = (1.0, 0.1);
    let sphere = Sphere::new(DVec3::new(0.1, -0.2, 0.3), r, false, DVec3::new(0.3, 0.4, 1.0)).unwrap();
    let shift = |c: Vec<Case>| c.into_iter().map(|c| Case { origin: c.origin + sphere.center, ..c }).collect::<Vec<_>>();
    let media = [
        ("beckmann_aniso", medium(Ndf::Beckmann(Beckmann::new(0.2, 0.6).unwrap()), sigma)),
        ("gpss_iso", medium(Ndf::Gpss(Gpss::new(1.0, 1.0, 1.0).unwrap()), sigma)),
    ];
    let cases = shift(sphere_cases(r, sigma));
    let alpha = sidak_alpha(0.01, 3 * cases.len() * media.len());
    let mut failures = 0;
    for (k, (name, m)) in media.iter().enumerate() {
        let (f, stats) = check_surface(name, m, &sphere, &cases, 3000, alpha, 11 + k as u64);
        failures += f;
        assert_eq!(stats.majorant_violations, 0, "{name}: majorant violated");
    }
    assert_eq!(failures, 0);
}

/// A spherical cavity (flipped normals: the opaque interior lies outside the sphere, the shell
/// lines its wall from inside) of radius 10σ: rays from the cavity reach the shell's top in one
/// exact step of the sphere's clearance (the exit of the level sphere), then track a concave
/// shell. Free flights and transmittance against the exact ones, no majorant violation.
#[test]
fn spherical_cavity_of_radius_ten_sigma() {
    let (r, sigma) = (1.0, 0.1);
    let c = DVec3::new(0.1, -0.2, 0.3);
    let cavity = Sphere::new(c, r, true, DVec3::new(0.3, 0.4, 1.0)).unwrap();
    let top = r - 3.0 * sigma; // the radius of the shell's top face
    // Each ray ends in the cavity or the shell, so that transmittance is not trivially 0.
    let cases = vec![
        ray("to_the_wall", c, c + DVec3::X, r - sigma),
        ray("oblique", c + DVec3::new(-0.5 * top, 0.3 * top, 0.0), c + DVec3::new(r, 0.5 * r, 0.1 * r), 1.2 * r),
        ray("grazing_top", c + DVec3::new(-0.5 * r, 0.0, top - 0.3 * sigma), c + DVec3::new(0.0, 0.0, top - 0.3 * sigma), r),
        ray("leaving_the_wall", c + DVec3::new(0.0, 0.0, r - 0.5 * sigma), c + DVec3::new(0.3, 0.0, 0.0), r),
    ];
    let m = medium(Ndf::Gpss(Gpss::new(1.0, 1.0, 1.0).unwrap()), sigma);
    let (failures, stats) = check_surface("cavity_gpss_iso", &m, &cavity, &cases, 3000, sidak_alpha(0.01, 3 * cases.len()), 21);
    assert_eq!(stats.majorant_violations, 0, "majorant violated");
    assert_eq!(failures, 0);
}

#[test]
fn meshes_with_sharp_and_reflex_edges_and_a_smooth_torus() {
    let gpss = |sigma| medium(Ndf::Gpss(Gpss::new(0.5, 0.3, 0.25).unwrap()), sigma);
    let cube = mesh_surface(&meshes::cube());
    let l = mesh_surface(&meshes::l_prism());
    let torus = mesh_surface(&meshes::torus(1.0, 0.4, 32, 16));
    let sigma = 0.02;
    let s = sigma;
    let cube_cases = vec![
        ray("edge_grazing", DVec3::new(-3.0, 1.0 + s, 1.0 + 2.0 * s), DVec3::new(3.0, 1.0 + s, 1.0 + 2.0 * s), 7.0),
        ray("corner", DVec3::new(-3.0, -3.0, 3.0), DVec3::new(1.0 + s, 1.0 + s, -1.0 - s), 8.0),
        ray("across_edge", DVec3::new(-1.5, 0.0, 1.3), DVec3::new(-0.7, 0.0, 0.95), 3.0),
        ray("inside_out", DVec3::new(0.9, 0.95, 0.99), DVec3::new(1.5, 1.5, 1.6), 2.0),
    ];
    let l_cases = vec![
        ray("into_reflex", DVec3::new(2.0, 2.0, 0.5), DVec3::new(1.0, 1.0, 0.5), 3.0),
        ray("along_reflex", DVec3::new(1.0 + s, 1.0 + s, -1.0), DVec3::new(1.0 + s, 1.0 + s, 2.0), 4.0),
        ray("skim_inner_faces", DVec3::new(3.0, 1.0 + 2.0 * s, 0.4), DVec3::new(0.5, 1.0 + 2.0 * s, 0.4), 4.0),
    ];
    let torus_cases = vec![
        ray("through_hole", DVec3::new(-3.0, 0.1, 0.2), DVec3::new(3.0, 0.1, 0.2), 7.0),
        ray("top_grazing", DVec3::new(-3.0, 0.0, 0.4 + s), DVec3::new(3.0, 0.0, 0.4 + s), 7.0),
        ray("oblique", DVec3::new(-2.0, -2.0, 2.0), DVec3::new(1.0, 0.3, 0.0), 6.0),
        ray("inner_rim", DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.6 - s, 0.0, 0.0), 3.0),
    ];
    let sets: [(&str, &TriangleMesh, &[Case]); 3] = [("cube", &cube, &cube_cases), ("l_prism", &l, &l_cases), ("torus", &torus, &torus_cases)];
    let n_tests: usize = sets.iter().map(|(_, _, c)| 3 * c.len()).sum();
    let alpha = sidak_alpha(0.01, n_tests);
    let mut failures = 0;
    for (k, (name, surface, cases)) in sets.iter().enumerate() {
        let (f, stats) = check_surface(name, &gpss(sigma), *surface, cases, 2000, alpha, 23 + k as u64);
        failures += f;
        assert_eq!(stats.majorant_violations, 0, "{name}: majorant violated");
    }
    assert_eq!(failures, 0);
}

#[test]
fn thin_shell_across_the_edges_of_a_torus_mesh() {
    // A thin shell (σ well below the edges' zones, `surface/mesh/edge.rs`) on a smooth torus,
    // with its vertex normals and flat: segments that cross an edge where no face region
    // certifies them take the dihedral bound of the edge's two triangles. And the smooth torus
    // built for this shell's reach (its top, 3σ), whose certified heights and grid stop 12σ out.
    let m = medium(Ndf::Gpss(Gpss::new(0.3, 0.3, 0.15).unwrap()), 0.002);
    let mesh = meshes::torus(1.0, 0.4, 32, 16);
    let smooth = mesh_surface(&mesh);
    let within_reach = mesh_surface_within(&mesh, m.height.top());
    let flat = mesh_surface(&Mesh { normals: None, ..mesh });
    let cases = vec![
        ray("oblique", DVec3::new(-2.0, -2.0, 2.0), DVec3::new(1.0, 0.3, 0.0), 6.0),
        ray("grazing_top", DVec3::new(-3.0, 0.05, 0.4), DVec3::new(3.0, 0.05, 0.4), 7.0),
        ray("inner_rim", DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.6, 0.0, 0.0), 3.0),
    ];
    let surfaces = [("smooth torus", &smooth), ("flat torus", &flat), ("smooth torus within the shell's reach", &within_reach)];
    for (k, (name, surface)) in surfaces.into_iter().enumerate() {
        let (failures, stats) = check_surface(name, &m, surface, &cases, 2000, sidak_alpha(0.01, 9 * cases.len()), 53 + k as u64);
        assert_eq!(stats.majorant_violations, 0, "{name}: majorant violated");
        assert_eq!(failures, 0);
    }
}

#[test]
fn thick_shell_around_a_torus_restarts_without_bias() {
    // A volume-like shell (isotropic gpss, σ = a fifth of the tube's radius, as the default
    // scene's third torus): away from the certified regions the mesh bounds segments by the
    // Lipschitz bound alone, and free flights (transmittances) start a new segment at each
    // rejected (residual) tentative collision.
    let m = medium(Ndf::Gpss(Gpss::new(1.0, 1.0, 1.0).unwrap()), 0.08);
    let torus = mesh_surface(&meshes::torus(1.0, 0.4, 32, 16));
    let cases = vec![
        ray("through_hole_low", DVec3::new(-3.0, 0.1, 0.3), DVec3::new(3.0, 0.1, 0.3), 7.0),
        ray("through_hole_high", DVec3::new(-3.0, 0.1, 0.38), DVec3::new(3.0, 0.1, 0.38), 7.0),
        ray("oblique", DVec3::new(-2.0, -2.0, 2.0), DVec3::new(1.0, 0.3, 0.0), 6.0),
        ray("inner_rim", DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.45, 0.0, 0.0), 3.0),
        ray("above_the_tube", DVec3::new(-3.0, 0.0, 0.55), DVec3::new(3.0, 0.0, 0.55), 7.0),
    ];
    let (failures, stats) = check_surface("thick torus", &m, &torus, &cases, 8000, sidak_alpha(0.01, 3 * cases.len()), 41);
    assert_eq!(stats.majorant_violations, 0, "thick torus: majorant violated");
    assert_eq!(failures, 0);
}

#[test]
fn brute_force_delta_tracking_agrees() {
    // Two-sample KS of free-flight distances (scattered) and a comparison of pass fractions.
    let m = medium(Ndf::Beckmann(Beckmann::new(0.3, 0.3).unwrap()), 0.1);
    let sphere = Sphere::new(DVec3::ZERO, 1.0, false, DVec3::Z).unwrap();
    let cube = mesh_surface(&meshes::cube());
    let s_max = largest_projected_area(&m.phase.ndf);
    let n = 4000;
    let cases_sphere = sphere_cases(1.0, 0.1);
    let cases_cube = [ray("corner", DVec3::new(-3.0, -3.0, 3.0), DVec3::new(1.1, 1.1, -1.1), 8.0), ray("edge", DVec3::new(-3.0, 1.1, 1.2), DVec3::new(3.0, 1.1, 1.2), 7.0)];
    let alpha = sidak_alpha(0.01, 2 * (cases_sphere.len() + cases_cube.len()));
    // One free flight (origin, direction, t_max, rng, tracker rather than brute force): Some(t) if it scatters.
    type FlightSampler<'a> = dyn Fn(DVec3, DVec3, f64, &mut Pcg32, bool) -> Option<f64> + 'a;
    let run = |label: &str, surface: &FlightSampler<'_>, case: &Case, k: u64| {
        let (mut a, mut b) = (Vec::new(), Vec::new());
        let mut rng = Pcg32::new(99, k);
        for _ in 0..n {
            if let Some(t) = surface(case.origin, case.d, case.t_max, &mut rng, true) {
                a.push(t);
            }
            if let Some(t) = surface(case.origin, case.d, case.t_max, &mut rng, false) {
                b.push(t);
            }
        }
        let p = if a.len() > 10 && b.len() > 10 { ks_two_sample(&mut a, &mut b) } else { 1.0 };
        let (pa, pb) = (1.0 - a.len() as f64 / n as f64, 1.0 - b.len() as f64 / n as f64);
        let pooled = 0.5 * (pa + pb);
        let se = (2.0 * pooled * (1.0 - pooled) / n as f64).sqrt();
        let z = if se > 0.0 { (pa - pb) / se } else { 0.0 };
        println!("{label}/{}: KS p {p:.3}, P(pass) tracker {pa:.4} vs brute force {pb:.4} (z {z:+.2})", case.name);
        assert!(p > alpha && 2.0 * normal_cdf(-z.abs()) > alpha, "{label}/{}: tracker and brute force disagree", case.name);
    };
    let tracker = Tracker::new(&m, &sphere);
    let flight = |o, d, t_max, rng: &mut Pcg32, fast: bool| {
        if fast {
            match tracker.sample_free_flight(o, d, t_max, rng, &mut TrackStats::default()).unwrap() {
                TrackedFlight::Scatter { t, .. } => Some(t),
                TrackedFlight::Pass => None,
            }
        } else {
            brute_force_flight(&tracker, &sphere, &m, s_max, o, d, t_max, rng)
        }
    };
    for (k, case) in cases_sphere.iter().enumerate() {
        run("sphere", &flight, case, k as u64);
    }
    let tracker = Tracker::new(&m, &cube);
    let flight = |o, d, t_max, rng: &mut Pcg32, fast: bool| {
        if fast {
            match tracker.sample_free_flight(o, d, t_max, rng, &mut TrackStats::default()).unwrap() {
                TrackedFlight::Scatter { t, .. } => Some(t),
                TrackedFlight::Pass => None,
            }
        } else {
            brute_force_flight(&tracker, &cube, &m, s_max, o, d, t_max, rng)
        }
    };
    for (k, case) in cases_cube.iter().enumerate() {
        run("cube", &flight, case, 100 + k as u64);
    }
}

#[test]
fn planar_surface_makes_every_tentative_collision_real() {
    // Near the centre of a large cube's face the mean surface is a plane: the majorant is σ_t.
    let m = medium(Ndf::Gpss(Gpss::new(0.4, 0.4, 0.2).unwrap()), 0.01);
    let mut big = meshes::cube();
    for p in &mut big.positions {
        *p *= 100.0;
    }
    let surface = mesh_surface(&big);
    let tracker = Tracker::new(&m, &surface);
    let mut stats = TrackStats::default();
    let mut rng = Pcg32::new(5, 5);
    let mut scatters = 0;
    for i in 0..2000 {
        let theta = 0.1 + 1.3 * (i as f64 / 2000.0);
        let d = DVec3::new(theta.sin(), 0.0, -theta.cos());
        let o = DVec3::new(0.0, 30.0, 100.05) - 0.02 * d;
        if let TrackedFlight::Scatter { .. } = tracker.sample_free_flight(o, d, 1.0, &mut rng, &mut stats).unwrap() {
            scatters += 1;
        }
    }
    println!("planar: {stats:?}, {scatters} scatters");
    assert_eq!(stats.majorant_violations, 0);
    assert_eq!(stats.tentative_collisions, scatters, "a tentative collision was rejected on a plane");
}

#[test]
fn mesh_distance_matches_brute_force_and_bounds_hold() {
    // The hierarchy's closest point equals the minimum over all triangles; along random short
    // segments near the surface, f and d·n stay within the segment bounds: for a thin shell's
    // tolerance and for a thick one's, where certified pieces shorter than a quarter of it
    // give way to the far bound; and on a surface built for a thin shell's reach (its closed
    // forms stop 0.012 out), at both tolerances and far from it.
    for (name, mesh) in [("torus", meshes::torus(1.0, 0.4, 24, 12)), ("l_prism", meshes::l_prism()), ("sphere", meshes::uv_sphere(1.0, 12, 24)), ("lumpy torus", meshes::lumpy_torus(1.0, 0.4, 32, 16, 0.15))] {
        let surface = mesh_surface(&mesh);
        let within_reach = mesh_surface_within(&mesh, 0.003);
        let flat = mesh_surface(&Mesh { normals: None, ..mesh });
        let mut rng = Pcg32::new(3, 4);
        let mut cache = Default::default();
        for _ in 0..3000 {
            let p = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 3.0 - DVec3::splat(1.0);
            let d = DVec3::new(rng.next_f64() - 0.5, rng.next_f64() - 0.5, rng.next_f64() - 0.5).normalize();
            for (s, tolerance) in [(&surface, 0.01), (&flat, 0.01), (&surface, 0.4), (&flat, 0.4), (&within_reach, 0.01), (&within_reach, 0.4)] {
                let start = s.point(p).unwrap();
                let length = 0.3 * rng.next_f64() + 1e-3;
                let b = s.bound(&start, p, d, length, tolerance, &mut cache).unwrap();
                b.validate(length, start.f, name).unwrap();
                let (lo0, lo_k) = b.lower_line();
                let (hi0, hi_k) = b.upper_line();
                for j in 0..=50 {
                    let t = b.length * j as f64 / 50.0;
                    let q = s.point_on_segment(p + t * d, &cache).unwrap();
                    let exact = s.point(p + t * d).unwrap();
                    assert!((q.f - exact.f).abs() <= 1e-12 * (1.0 + exact.f.abs()), "{name}: cached query differs");
                    let tol = 1e-9 * (1.0 + q.f.abs());
                    assert!(q.f >= lo0 + lo_k * t - tol && q.f <= hi0 + hi_k * t + tol, "{name}: f = {} outside [{}, {}] at s = {t}", q.f, lo0 + lo_k * t, hi0 + hi_k * t);
                    let c = d.dot(q.normal);
                    assert!(c >= b.cos[0] - 1e-9 && c <= b.cos[1] + 1e-9, "{name}: d.n = {c} outside {:?}", b.cos);
                }
            }
        }
    }
}

/// The distance from `p` to triangle `abc` by projection on its plane and, outside, the nearest
/// of its edges (independent of the library's Ericson-style search).
fn brute_triangle_distance(p: DVec3, [a, b, c]: [DVec3; 3]) -> f64 {
    let segment = |u: DVec3, v: DVec3| {
        let e = v - u;
        let s = ((p - u).dot(e) / e.length_squared()).clamp(0.0, 1.0);
        (p - (u + s * e)).length()
    };
    let edges = segment(a, b).min(segment(b, c)).min(segment(c, a));
    let n = (b - a).cross(c - a);
    if n.length_squared() == 0.0 {
        return edges;
    }
    let n = n.normalize();
    let q = p - n.dot(p - a) * n;
    let inside = [(a, b), (b, c), (c, a)].iter().all(|&(u, v)| (v - u).cross(q - u).dot(n) >= 0.0);
    if inside { n.dot(p - a).abs() } else { edges }
}

#[test]
fn mesh_distance_is_exact_near_the_surface() {
    // |f| against the minimum over every triangle and its sign against the parity of ray
    // crossings, at points near the surface where most queries of a thin shell are settled by
    // one triangle's certified region: sharp convex and reflex edges (L prism), a smooth saddle
    // (torus), and an irregular lumpy surface whose every dihedral angle differs.
    let cases = [
        ("torus", meshes::torus(1.0, 0.4, 24, 12)),
        ("l_prism", meshes::l_prism()),
        ("lumpy torus", meshes::lumpy_torus(1.0, 0.4, 32, 16, 0.15)),
        ("coarse sphere", meshes::uv_sphere(1.0, 6, 8)),
        ("torus with zero-area triangles", meshes::torus(1.0, 0.4, 24, 12)),
    ];
    let mut checked = 0;
    for (name, mut mesh) in cases {
        let faces = mesh.indices.len();
        if name.contains("zero-area") {
            // Slivers along every third edge: they change no distance and must certify nothing.
            for t in (0..faces).step_by(3) {
                let [a, b, _] = mesh.indices[t];
                mesh.indices.extend([[a, a, b], [a, b, b]]);
            }
        }
        let surface = mesh_surface(&mesh);
        // Built for media tracked up to 0.005 from it: its certified heights and grid stop at
        // 0.02, and the points' heights (up to 0.05) reach past that.
        let within_reach = mesh_surface_within(&mesh, 0.005);
        let mut rng = Pcg32::new(11, 5);
        let scale = 0.05;
        for _ in 0..4000 {
            // A point over a random triangle, at a height concentrated near the surface.
            let [a, b, c] = mesh.indices[(rng.next_f64() * faces as f64) as usize].map(|i| mesh.positions[i as usize]);
            let (u, v) = (rng.next_f64(), rng.next_f64());
            let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
            let n = (b - a).cross(c - a).normalize();
            let height = scale * (2.0 * rng.next_f64() - 1.0).powi(3);
            let p = a + u * (b - a) + v * (c - a) + height * n;
            let f = surface.point(p).unwrap().f;
            let brute = mesh.indices.iter().map(|t| brute_triangle_distance(p, t.map(|i| mesh.positions[i as usize]))).fold(f64::INFINITY, f64::min);
            assert!((f.abs() - brute).abs() <= 1e-9, "{name}: |f({p})| = {} but the nearest triangle is at {brute}", f.abs());
            let f_within = within_reach.point(p).unwrap().f;
            assert!((f_within - f).abs() <= 1e-12 * (1.0 + f.abs()), "{name}: f({p}) = {f}, but {f_within} on the surface built for a reach of 0.005");
            if brute > 1e-6 {
                let d = DVec3::new(0.5377, 0.8131, 0.2231).normalize();
                let inside = crossings(&mesh.positions, &mesh.indices, p, d) % 2 == 1;
                assert_eq!(f < 0.0, inside, "{name}: f({p}) = {f} has the wrong sign");
            }
            checked += 1;
        }
    }
    assert_eq!(checked, 20000);
}

/// The distances `t` at which the line `o + t d` crosses the triangles of a mesh (Möller–Trumbore).
fn hits<'a>(positions: &'a [DVec3], triangles: &'a [[u32; 3]], o: DVec3, d: DVec3) -> impl Iterator<Item = f64> + 'a {
    triangles.iter().filter_map(move |t| {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let (e1, e2) = (b - a, c - a);
        let pv = d.cross(e2);
        let det = e1.dot(pv);
        if det.abs() < 1e-14 {
            return None;
        }
        let tv = o - a;
        let (u, qv) = (tv.dot(pv) / det, tv.cross(e1));
        let v = d.dot(qv) / det;
        (u >= 0.0 && v >= 0.0 && u + v <= 1.0).then(|| e2.dot(qv) / det)
    })
}

/// Crossings of the ray `o + t d`, `t > 0`, with a triangle mesh.
fn crossings(positions: &[DVec3], triangles: &[[u32; 3]], o: DVec3, d: DVec3) -> usize {
    hits(positions, triangles, o, d).filter(|&t| t > 0.0).count()
}

#[test]
fn enclosure_contains_the_region() {
    // Every point with f < level lies inside the enclosure (odd crossing count along a random
    // direction): random points of the surface's box, and points pushed to just below the level
    // set; every point of the enclosure's faces has f >= level. For a sphere (the voxel
    // enclosure), a smooth torus mesh, a sharp cube, an L-shaped prism with a reflex edge (each
    // the mesh's own faces moved out), a lumpy torus (saddles and concave bumps, whose faces
    // moved out by the thick level turn over: the voxel enclosure there) and a U-shaped prism
    // whose slot is narrower than twice the thick level (likewise), thin and thick levels.
    let torus = mesh_surface(&meshes::torus(1.0, 0.4, 32, 16));
    let cube = mesh_surface(&meshes::cube());
    let l_prism = mesh_surface(&meshes::l_prism());
    let lumpy = mesh_surface(&meshes::lumpy_torus(1.0, 0.4, 32, 16, 0.15));
    let slot = mesh_surface(&meshes::prism(&[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.51, 1.0), (0.51, 0.3), (0.49, 0.3), (0.49, 1.0), (0.0, 1.0)], 1.0));
    let sphere = Sphere::new(DVec3::new(0.2, 0.0, -0.1), 0.8, false, DVec3::Z).unwrap();
    fn check<S: MeanSurface>(name: &str, s: &S, level: f64, offset: bool, seed: u64) {
        let start = std::time::Instant::now();
        let e = macrofacet::surface::enclosure(s, level, 0.0).unwrap();
        let built = start.elapsed().as_secs_f64();
        assert_eq!(e.cell == 0.0, offset, "{name}, level {level}: the offset enclosure was{} expected", if offset { "" } else { " not" });
        let b = s.bounding_box().grown(level + 2.0 * e.cell);
        let mut rng = Pcg32::new(seed, 0);
        let (mut inside, mut near) = (0, 0);
        // Directions with irrational-ish components avoid edges of the axis-aligned faces.
        let d = DVec3::new(0.5377, 0.8131, 0.2231).normalize();
        for k in 0..2000 {
            let mut p = b.min + (b.max - b.min) * DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            if k % 2 == 1 {
                // Along the gradient to f = level (1 − u³): the shell's top, where a loose offset
                // would leave points out.
                let q = s.point(p).unwrap();
                p += (level * (1.0 - rng.next_f64().powi(3)) - q.f) * q.normal;
                near += 1;
            }
            let f = s.point(p).unwrap().f;
            if f < level {
                inside += 1;
                assert_eq!(crossings(&e.positions, &e.triangles, p, d) % 2, 1, "{name}: point {p} with f = {f} < {level} is outside the enclosure");
            }
        }
        for _ in 0..2000 {
            let t = e.triangles[(rng.next_f64() * e.triangles.len() as f64) as usize].map(|i| e.positions[i as usize]);
            let (u, v) = (rng.next_f64(), rng.next_f64());
            let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
            let p = t[0] + u * (t[1] - t[0]) + v * (t[2] - t[0]);
            let f = s.point(p).unwrap().f;
            assert!(f >= level, "{name}: the enclosure's point {p} has f = {f} < {level}");
            // The exit level bounds f on the faces, and just inside them (moved toward the
            // region along the face's normal, by a hundredth of the level).
            assert!(f <= e.exit_level, "{name}: the enclosure's point {p} has f = {f} above its exit level {}", e.exit_level);
            let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
            let q = p - 0.01 * level * n;
            if crossings(&e.positions, &e.triangles, q, d) % 2 == 1 {
                let f = s.point(q).unwrap().f;
                assert!(f <= e.exit_level, "{name}: {q} inside the enclosure has f = {f} above its exit level {}", e.exit_level);
            }
        }
        // Every point inside has f <= exit_level, which is at least the level.
        assert!(e.exit_level >= level);
        for _ in 0..2000 {
            let p = b.min + (b.max - b.min) * DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            if crossings(&e.positions, &e.triangles, p, d) % 2 == 1 {
                let f = s.point(p).unwrap().f;
                assert!(f <= e.exit_level, "{name}: {p} inside the enclosure has f = {f} above its exit level {}", e.exit_level);
            }
        }
        println!("{name}, level {level}: {} triangles, cell {:.4}, exit level {:.4}, built in {built:.2} s, {inside} region points inside ({near} pushed to the top)", e.triangles.len(), e.cell, e.exit_level);
    }
    for level in [0.003, 0.15] {
        check("torus", &torus, level, true, 1);
        check("cube", &cube, level, true, 2);
        check("L prism", &l_prism, level, true, 4);
        check("lumpy torus", &lumpy, level, level < 0.01, 6);
        check("slot", &slot, level, level < 0.01, 5);
        check("sphere", &sphere, level, false, 3);
    }
}

/// The first crossing after `t0` of the ray `o + t d` with a triangle mesh.
fn first_crossing(positions: &[DVec3], triangles: &[[u32; 3]], o: DVec3, d: DVec3, t0: f64) -> Option<f64> {
    hits(positions, triangles, o, d).filter(|&t| t > t0).min_by(f64::total_cmp)
}

#[test]
fn flights_that_find_their_exit_agree_with_ray_casts() {
    // A host that lets the tracker find the ray's exit from the enclosure (exit level) and one
    // that casts the ray to each exit and entry of the enclosure see the same first collision
    // along whole rays through a torus shell (thin: the mesh's own enclosure; thick: the
    // voxel one), and the same transmittance; where the tracker reports an exit, the ray is
    // outside the enclosure. Rays start inside the enclosure: on the mean surface and on the
    // enclosure's faces, in random directions (some cross the hole into the other side).
    let torus = mesh_surface(&meshes::torus(1.0, 0.4, 32, 16));
    for (k, sigma) in [0.001, 0.03].into_iter().enumerate() {
        let m = medium(Ndf::Beckmann(Beckmann::new(0.3, 0.3).unwrap()), sigma);
        let tracker = Tracker::new(&m, &torus);
        let e = macrofacet::surface::enclosure(&torus, m.height.top(), 0.0).unwrap();
        let mut rng = Pcg32::new(71 + k as u64, 0);
        let inside = |p: DVec3| crossings(&e.positions, &e.triangles, p, DVec3::new(0.5377, 0.8131, 0.2231).normalize()) % 2 == 1;
        let mut stats = TrackStats::default();
        // The whole ray cast at the enclosure: the first collision, or None.
        let cast = |o: DVec3, d: DVec3, rng: &mut Pcg32, stats: &mut TrackStats| -> (Option<f64>, f64) {
            let (mut t, mut transmittance) = (0.0, 1.0);
            loop {
                let exit = first_crossing(&e.positions, &e.triangles, o, d, t).unwrap();
                let p = o + t * d;
                if let TrackedFlight::Scatter { t: s, .. } = tracker.sample_free_flight(p, d, exit - t, rng, stats).unwrap() {
                    return (Some(t + s), 0.0);
                }
                transmittance *= tracker.transmittance(p, d, exit - t, rng, stats).unwrap();
                match first_crossing(&e.positions, &e.triangles, o, d, exit) {
                    Some(entry) => t = entry,
                    None => return (None, transmittance),
                }
            }
        };
        let mut exits = 0;
        let mut own = |o: DVec3, d: DVec3, rng: &mut Pcg32, stats: &mut TrackStats| -> (Option<f64>, f64) {
            let (mut t, mut transmittance) = (0.0, 1.0);
            loop {
                let p = o + t * d;
                let (flight, end) = tracker.sample_free_flight_to_exit(p, d, f64::INFINITY, e.exit_level, rng, stats).unwrap();
                if let TrackedFlight::Scatter { t: s, .. } = flight {
                    return (Some(t + s), 0.0);
                }
                let (tr, end_t) = tracker.transmittance_to_exit(p, d, f64::INFINITY, e.exit_level, rng, stats).unwrap();
                transmittance *= tr;
                // Both calls end outside the enclosure (or where the estimate reached 0).
                for at in [end].into_iter().chain((tr > 0.0).then_some(end_t)) {
                    let q = p + at * d;
                    assert!(!inside(q), "sigma {sigma}: the exit {q} lies inside the enclosure");
                    exits += 1;
                }
                match first_crossing(&e.positions, &e.triangles, o, d, t + end) {
                    Some(entry) => t = entry,
                    None => return (None, transmittance),
                }
            }
        };
        let n = 3000;
        let (mut a, mut b) = (Vec::new(), Vec::new());
        let (mut pass_a, mut pass_b, mut tr_a, mut tr_b) = (0, 0, Vec::new(), Vec::new());
        for i in 0..n {
            let origin = if i % 2 == 0 {
                // a point of the mean surface
                let q = DVec3::new(rng.next_f64() - 0.5, rng.next_f64() - 0.5, rng.next_f64() - 0.5) * 3.0;
                let s = torus.point(q).unwrap();
                q - s.f * s.normal
            } else {
                let t = e.triangles[(rng.next_f64() * e.triangles.len() as f64) as usize].map(|i| e.positions[i as usize]);
                let (u, v) = (rng.next_f64(), rng.next_f64());
                let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
                let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
                t[0] + u * (t[1] - t[0]) + v * (t[2] - t[0]) - 1e-6 * n
            };
            if !inside(origin) {
                continue;
            }
            let z = 2.0 * rng.next_f64() - 1.0;
            let phi = std::f64::consts::TAU * rng.next_f64();
            let d = DVec3::new((1.0 - z * z).sqrt() * phi.cos(), (1.0 - z * z).sqrt() * phi.sin(), z);
            let (fa, ta) = cast(origin, d, &mut rng, &mut stats);
            let (fb, tb) = own(origin, d, &mut rng, &mut stats);
            match fa {
                Some(t) => a.push(t),
                None => pass_a += 1,
            }
            match fb {
                Some(t) => b.push(t),
                None => pass_b += 1,
            }
            tr_a.push(ta);
            tr_b.push(tb);
        }
        let rays = a.len() + pass_a;
        let p = ks_two_sample(&mut a, &mut b);
        let (pa, pb) = (pass_a as f64 / rays as f64, pass_b as f64 / rays as f64);
        let z_pass = (pa - pb) / ((pa * (1.0 - pa) + pb * (1.0 - pb)) / rays as f64).sqrt().max(1e-12);
        let ((ma, sa), (mb, sb)) = (mean_and_standard_error(tr_a.iter().copied()), mean_and_standard_error(tr_b.iter().copied()));
        let z_tr = (ma - mb) / (sa * sa + sb * sb).sqrt().max(1e-12);
        println!("sigma {sigma}: {rays} rays, exit level {:.5}, {exits} exits checked, collision KS p = {p:.3}, passing {pa:.4} vs {pb:.4} (z = {z_pass:.2}), transmittance {ma:.4} vs {mb:.4} (z = {z_tr:.2})", e.exit_level);
        assert!(rays > 1000 && exits > 500);
        assert!(p > 1e-3, "sigma {sigma}: collision distances differ, KS p = {p}");
        assert!(z_pass.abs() < 3.5 && z_tr.abs() < 3.5, "sigma {sigma}: passing z = {z_pass}, transmittance z = {z_tr}");
        assert_eq!(stats.majorant_violations, 0);
    }
}

/// A field over a unit sphere: `σ` jumps across the plane `x = 0`, the roughness grows with `y`;
/// or a world-fixed anisotropy `Σ` (seeds/004 Eq. 25) whose axes leave the surface's frame. The
/// bounds come from the segment's extent in `x` and `y` (both parameters are monotone in them);
/// `understate` reports the larger σ as if constant, to test that wrong bounds are counted.
struct TestField {
    sigma: [f64; 2],
    alpha: [f64; 2],
    anisotropy: Option<glam::DMat3>,
    understate: bool,
}

impl TestField {
    fn alpha_at(&self, y: f64) -> f64 {
        self.alpha[0] + (self.alpha[1] - self.alpha[0]) * ((y + 1.5) / 3.0).clamp(0.0, 1.0)
    }
    fn sigma_at(&self, x: f64) -> f64 {
        if x < 0.0 { self.sigma[0] } else { self.sigma[1] }
    }
}

impl MediumField for TestField {
    fn at(&self, p: DVec3, _: &macrofacet::surface::SurfacePoint) -> macrofacet::Result<LocalParams> {
        let sigma = self.sigma_at(p.x);
        Ok(match self.anisotropy {
            Some(a) => LocalParams { sigma: Some(sigma), anisotropy: Some(a), ..Default::default() },
            None => LocalParams { sigma: Some(sigma), alpha: Some(DVec3::new(self.alpha_at(p.y), 0.7 * self.alpha_at(p.y), 0.5)), ..Default::default() },
        })
    }
    fn bounds(&self, p: DVec3, d: DVec3, length: f64) -> macrofacet::Result<ParamBounds> {
        let q = p + length * d;
        let sigma = [self.sigma_at(p.x.min(q.x)), self.sigma_at(p.x.max(q.x))];
        let alpha = match self.anisotropy {
            // √λ(2σ²Σ⁻¹) over Σ's eigenvalues (its diagonal here) and the σ range.
            Some(a) => {
                let l = [a.x_axis.x, a.y_axis.y, a.z_axis.z];
                let (lmin, lmax) = (l.iter().copied().fold(f64::INFINITY, f64::min), l.iter().copied().fold(0.0, f64::max));
                [(2.0f64).sqrt() * sigma[0] / lmax.sqrt(), (2.0f64).sqrt() * sigma[1] / lmin.sqrt()]
            }
            None => {
                let (a, b) = (self.alpha_at(p.y.min(q.y)), self.alpha_at(p.y.max(q.y)));
                [0.7 * a.min(0.5 / 0.7), b.max(0.5)]
            }
        };
        let sigma = if self.understate { [self.sigma[1], self.sigma[1]] } else { sigma };
        Ok(ParamBounds { sigma: Some(sigma), alpha: Some(alpha) })
    }
    fn sigma_max(&self) -> Option<f64> {
        Some(self.sigma[1])
    }
}

#[test]
fn spatially_varying_fields_track_without_bias() {
    // Issue 12: σ jumping across x = 0 and a roughness growing along y, then a world-fixed
    // anisotropy Σ that couples the normal and the tangents on the sphere; free flights against
    // the exact distribution and transmittance against exp(-τ), τ by quadrature of the local σ_t.
    let sphere = Sphere::new(DVec3::ZERO, 1.0, false, DVec3::Z).unwrap();
    let gpss = medium(Ndf::Gpss(Gpss::new(0.3, 0.3, 0.5).unwrap()), 0.05);
    let beckmann = medium(Ndf::Beckmann(Beckmann::new(0.3, 0.3).unwrap()), 0.05);
    let stepped = TestField { sigma: [0.03, 0.08], alpha: [0.15, 0.8], anisotropy: None, understate: false };
    let aniso = TestField { sigma: [0.05, 0.05], alpha: [0.0, 0.0], anisotropy: Some(glam::DMat3::from_diagonal(DVec3::new(0.04, 0.25, 0.01))), understate: false };
    let mut cases = sphere_cases(1.0, 0.05);
    cases.push(ray("across_the_step", DVec3::new(-3.0, 0.2, 1.02), DVec3::new(3.0, 0.2, 1.02), 6.0));
    let runs: [(&str, &MacrofacetMedium, &TestField); 3] = [("gpss stepped", &gpss, &stepped), ("beckmann stepped", &beckmann, &stepped), ("gpss anisotropy", &gpss, &aniso)];
    let alpha = sidak_alpha(0.01, 3 * cases.len() * runs.len());
    let mut failures = 0;
    for (k, (name, m, field)) in runs.iter().enumerate() {
        let (f, stats) = check_field(name, m, &sphere, *field, 0.03, &cases, 2000, alpha, 41 + k as u64);
        failures += f;
        assert_eq!(stats.majorant_violations, 0, "{name}: majorant violated");
    }
    assert_eq!(failures, 0);

    // Bounds that claim the larger σ where the smaller holds (so ρ below the mean surface is
    // underestimated) are caught: violations are counted.
    let liar = TestField { understate: true, ..stepped };
    let tracker = Tracker::with_field(&gpss, &sphere, &liar);
    let mut stats = TrackStats::default();
    for i in 0..2000 {
        let mut rng = Pcg32::new(i, 3);
        let o = DVec3::new(-3.0, 0.2 * rng.next_f64(), 0.1);
        tracker.sample_free_flight(o, DVec3::X, 6.0, &mut rng, &mut stats).unwrap();
    }
    assert!(stats.majorant_violations > 0, "understated bounds went unnoticed");
}

#[test]
fn a_field_of_the_medium_s_own_values_changes_nothing() {
    // Issue 12: constant parameters given through a field equal the scalar medium (same seed:
    // identical free flights; transmittance estimates identical too while σ is known).
    struct Same(f64);
    impl MediumField for Same {
        fn at(&self, _: DVec3, _: &macrofacet::surface::SurfacePoint) -> macrofacet::Result<LocalParams> {
            Ok(LocalParams { sigma: Some(self.0), ..Default::default() })
        }
        fn bounds(&self, _: DVec3, _: DVec3, _: f64) -> macrofacet::Result<ParamBounds> {
            Ok(ParamBounds { sigma: Some([self.0, self.0]), alpha: None })
        }
        fn sigma_max(&self) -> Option<f64> {
            Some(self.0)
        }
    }
    let sphere = Sphere::new(DVec3::ZERO, 1.0, false, DVec3::Z).unwrap();
    let m = medium(Ndf::Gpss(Gpss::new(0.3, 0.5, 0.2).unwrap()), 0.05);
    let (plain, field) = (Tracker::new(&m, &sphere), Tracker::with_field(&m, &sphere, &Same(0.05)));
    for (k, case) in sphere_cases(1.0, 0.05).iter().enumerate() {
        for i in 0..300 {
            let seed = (k * 1000 + i) as u64;
            let (mut s0, mut s1) = (TrackStats::default(), TrackStats::default());
            let a = plain.sample_free_flight(case.origin, case.d, case.t_max, &mut Pcg32::new(seed, 1), &mut s0).unwrap();
            let b = field.sample_free_flight(case.origin, case.d, case.t_max, &mut Pcg32::new(seed, 1), &mut s1).unwrap();
            match (a, b) {
                (TrackedFlight::Scatter { t: ta, .. }, TrackedFlight::Scatter { t: tb, .. }) => assert_eq!(ta.to_bits(), tb.to_bits(), "{}", case.name),
                (TrackedFlight::Pass, TrackedFlight::Pass) => {}
                other => panic!("{}: {other:?}", case.name),
            }
            let ta = plain.transmittance(case.origin, case.d, case.t_max, &mut Pcg32::new(seed, 2), &mut s0).unwrap();
            let tb = field.transmittance(case.origin, case.d, case.t_max, &mut Pcg32::new(seed, 2), &mut s1).unwrap();
            assert_eq!(ta.to_bits(), tb.to_bits(), "{}: transmittance", case.name);
        }
    }
}

/// A field that declares fixed bounds and answers `sigma` everywhere.
struct Declared(ParamBounds, f64);
impl MediumField for Declared {
    fn at(&self, _: DVec3, _: &macrofacet::surface::SurfacePoint) -> macrofacet::Result<LocalParams> {
        Ok(LocalParams { sigma: Some(self.1), ..Default::default() })
    }
    fn bounds(&self, _: DVec3, _: DVec3, _: f64) -> macrofacet::Result<ParamBounds> {
        Ok(self.0)
    }
    fn sigma_max(&self) -> Option<f64> {
        Some(self.1)
    }
}

#[test]
fn field_bounds_beyond_the_parameter_domain() {
    // fuzz/artifacts (fields, timeout-c7e829a2…): a field declaring α in [5.4e264, 1.1e265]
    // put a projected area of ~1e265 into the majorant; the transmittance's thinning never asked
    // the field for a value and the call failed after 131,072 tentative collisions. Bounds with
    // no value of the domain now fail at the first segment, with the reason; bounds reaching
    // beyond it are clipped (values there are refused where the field is evaluated).
    let sphere = Sphere::new(DVec3::ZERO, 1.0, false, DVec3::Z).unwrap();
    let m = medium(Ndf::Gpss(Gpss::new(0.3, 0.3, 0.0).unwrap()), 0.05);
    let (o, d) = (DVec3::new(-3.0, 0.1, 0.0), DVec3::X);
    for (bounds, needle) in [
        (ParamBounds { sigma: Some([0.05, 0.05]), alpha: Some([5.4e264, 1.1e265]) }, "alpha bounds [5.4e264, 1.1e265] leave no value"),
        (ParamBounds { sigma: Some([2e50, 3e50]), alpha: None }, "sigma bounds [2e50, 3e50] leave no value"),
    ] {
        let field = Declared(bounds, 0.05);
        let tracker = Tracker::with_field(&m, &sphere, &field);
        let mut stats = TrackStats::default();
        let e = tracker.transmittance(o, d, 6.0, &mut Pcg32::new(1, 2), &mut stats).unwrap_err();
        assert!(e.message.contains(needle), "{}", e.message);
        assert_eq!(stats.tentative_collisions, 0, "{stats:?}");
    }
    // Bounds reaching beyond the domain are clipped to it (α_lo may be 0: α_z of a height field).
    let clipped = ParamBounds { sigma: Some([1e-60, 0.05]), alpha: Some([0.0, 1e9]) }.validated("test").unwrap();
    assert_eq!((clipped.sigma, clipped.alpha), (Some([1e-50, 0.05]), Some([0.0, 1e6])));
}

#[test]
fn surface_points_carry_mitsuba_uv() {
    // Issue 12: fields painted over the mean surface read Mitsuba's uv at the closest point —
    // interpolated texture coordinates on meshes (barycentrics without them), the polar angle
    // and azimuth about the pole on spheres.
    let octa: Vec<DVec3> = [DVec3::X, -DVec3::X, DVec3::Y, -DVec3::Y, DVec3::Z, -DVec3::Z].into();
    let tris = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
    let uvs: Vec<DVec2> = (0..6).map(|i| DVec2::new(0.1 * i as f64, 1.0 - 0.15 * i as f64)).collect();
    let with_uv = TriangleMesh::new(&octa, &tris, None, Some(&uvs), 1, f64::INFINITY).unwrap();
    let without = TriangleMesh::new(&octa, &tris, None, None, 1, f64::INFINITY).unwrap();
    // Above the centroid of face (0, 2, 4): barycentrics 1/3 each.
    let p = (DVec3::X + DVec3::Y + DVec3::Z) / 3.0 * 1.2;
    let expect = (uvs[0] + uvs[2] + uvs[4]) / 3.0;
    assert!((with_uv.point(p).unwrap().uv - expect).length() < 1e-12);
    assert!((without.point(p).unwrap().uv - DVec2::splat(1.0 / 3.0)).length() < 1e-12);
    let sphere = Sphere::new(DVec3::new(1.0, 2.0, 3.0), 0.5, false, DVec3::Z).unwrap();
    let (x_axis, y_axis) = DVec3::Z.any_orthonormal_pair();
    let at = |theta: f64, phi: f64| sphere.point(sphere.center + 0.7 * (theta.sin() * (phi.cos() * x_axis + phi.sin() * y_axis) + theta.cos() * DVec3::Z)).unwrap().uv;
    for (theta, phi) in [(0.3, 0.4), (1.2, 2.9), (2.8, 4.0), (std::f64::consts::FRAC_PI_2, 6.0)] {
        let uv = at(theta, phi);
        assert!((uv - DVec2::new(phi / std::f64::consts::TAU, theta / std::f64::consts::PI)).length() < 1e-12, "({theta}, {phi}): {uv}");
    }
}

/// A sphere's tracker queries leave out the uv (its two angles cost as much as the rest); a
/// collision still reports the uv `point` gives there, and a field still reads it.
#[test]
fn sphere_collisions_carry_the_uv_the_tracker_left_out() {
    let sphere = Sphere::new(DVec3::new(0.1, -0.2, 0.3), 1.0, false, DVec3::new(0.3, 0.4, 1.0)).unwrap();
    let m = medium(Ndf::Beckmann(Beckmann::new(0.3, 0.3).unwrap()), 1e-3);
    let tracker = Tracker::new(&m, &sphere);
    let mut rng = Pcg32::new(5, 5);
    let mut scattered = 0;
    for i in 0..200 {
        let n = DVec3::new(rng.next_f64() - 0.5, rng.next_f64() - 0.5, rng.next_f64() - 0.5).normalize();
        let (o, d) = (sphere.center + 1.01 * n, -n);
        let flight = tracker.sample_free_flight(o, d, f64::INFINITY, &mut Pcg32::new(i, 1), &mut TrackStats::default()).unwrap();
        let TrackedFlight::Scatter { t, point, .. } = flight else { continue };
        scattered += 1;
        let exact = sphere.point(o + t * d).unwrap();
        assert!((point.uv - exact.uv).length() < 1e-12 && point.uv != DVec2::ZERO, "uv {} at a collision where point() gives {}", point.uv, exact.uv);
    }
    assert!(scattered > 190, "{scattered} of 200 rays into the shell scattered");
}

/// A sphere's clearance is the ray's crossing of the level sphere itself: the tracker crosses
/// the empty space above the shell in one step, even right above the top face, and a shadow ray
/// that leaves the shell takes one segment. The step never overshoots the level (the first
/// factor of `|v|² − R²` comes from `f`, without the cancellation of the squares).
#[test]
fn sphere_clearance_crosses_the_gap_above_the_shell_in_one_step() {
    let sphere = Sphere::new(DVec3::new(0.1, -0.2, 0.3), 1.0, false, DVec3::Z).unwrap();
    let m = medium(Ndf::Beckmann(Beckmann::new(0.3, 0.3).unwrap()), 1e-3);
    let (top, tracker) = (m.height.top(), Tracker::new(&m, &sphere));
    let mut rng = Pcg32::new(8, 8);
    for _ in 0..2000 {
        let n = DVec3::new(rng.next_f64() - 0.5, rng.next_f64() - 0.5, rng.next_f64() - 0.5).normalize();
        let d = DVec3::new(rng.next_f64() - 0.5, rng.next_f64() - 0.5, rng.next_f64() - 0.5).normalize();
        // From 1e-12 to 1 above the top face, toward the sphere or away from it.
        let p = sphere.center + (1.0 + top + 10f64.powf(-12.0 * rng.next_f64())) * n;
        let start = sphere.point(p).unwrap();
        let step = sphere.clearance(&start, p, d, top, &mut ());
        assert!(step >= start.f - top, "a step of {step} below the Lipschitz step {}", start.f - top);
        if step.is_finite() {
            let reached = sphere.point(p + step * d).unwrap();
            assert!(reached.f >= top - 1e-15, "from f = {} along {d}: the step {step} overshot the level to f = {}", start.f, reached.f);
        }
    }
    // Shadow rays from inside the shell that leave it: one segment, then one step to the exit.
    for i in 0..200 {
        let n = DVec3::new(rng.next_f64() - 0.5, rng.next_f64() - 0.5, rng.next_f64() - 0.5).normalize();
        let (a, _) = n.any_orthonormal_pair();
        let d = (n + 0.5 * a).normalize();
        let mut stats = TrackStats::default();
        tracker.transmittance(sphere.center + (1.0 + m.height.sigma) * n, d, f64::INFINITY, &mut Pcg32::new(i, 2), &mut stats).unwrap();
        assert_eq!(stats.segments, 1, "a shadow ray leaving the shell: {stats:?}");
    }
}

/// A sphere's exact signed distance sampled on an `n³` grid over the unit cube, placed by a
/// rotation, a uniform scale and a translation (Mitsuba's `sdfgrid` convention).
fn sphere_grid(n: usize, radius_object: f64) -> (macrofacet::surface::GridSurface, glam::DMat3, DVec3) {
    let values: Vec<f32> = (0..n * n * n)
        .map(|i| {
            let (x, y, z) = (i % n, (i / n) % n, i / (n * n));
            let p = DVec3::new(x as f64, y as f64, z as f64) / (n - 1) as f64;
            ((p - DVec3::splat(0.5)).length() - radius_object) as f32
        })
        .collect();
    let linear = glam::DMat3::from_rotation_y(0.4) * glam::DMat3::from_rotation_z(0.9) * 2.0;
    let translation = DVec3::new(0.3, -0.2, 1.0);
    (macrofacet::surface::GridSurface::new(&values, [n, n, n], linear, translation).unwrap(), linear, translation)
}

#[test]
fn sdf_grid_bound_of_a_segment_far_beyond_the_grid() {
    // fuzz/artifacts/tracking/crash-f4fba2b466b986a109931cb066f2682c2877f9cc: σ = 1e50 makes
    // segments 1e50 long, whose grid coordinates overflowed i32 in `lipschitz_along` (a panic;
    // wrapped, no cell would have been bounded). The bound must still hold at the far end.
    let (grid, _, _) = sphere_grid(8, 0.3);
    let p = DVec3::new(1e-16, 1e-16, 0.5);
    let d = DVec3::new(2.1073424255447017e-8, 0.0, -1.0).normalize();
    let start = grid.point(p).unwrap();
    // A longer segment from the same start crosses every cell a shorter one does.
    let slope = |length: f64| grid.bound(&start, p, d, length, 1.0, &mut ()).unwrap().upper_line().1;
    let leaving = slope(10.0);
    for length in [1.0, 1e10, 1e50, 1e100] {
        let bound = grid.bound(&start, p, d, length, 1.0, &mut ()).unwrap();
        let end = grid.point(p + bound.length * d).unwrap();
        let (lo, hi) = (bound.lower_line(), bound.upper_line());
        let at_end = |(v, k): (f64, f64)| v + k * bound.length;
        assert!(at_end(lo) <= end.f && end.f <= at_end(hi), "length {length}: f = {} outside [{}, {}]", end.f, at_end(lo), at_end(hi));
        assert!(length < 10.0 || hi.1 >= leaving, "length {length}: slope {} below the {leaving} of a shorter segment", hi.1);
    }
}

#[test]
fn sdf_grid_surface_interpolates_bounds_and_tracks() {
    // Issue 12: a mean surface from an SDF grid. The trilinear interpolant of a sphere's distance
    // is within O(h²) of it and exact at the samples; segment bounds hold inside and beyond the
    // grid; free flights and transmittance match quadrature with no majorant violation.
    let (grid, linear, translation) = sphere_grid(48, 0.3);
    let centre = linear * DVec3::splat(0.5) + translation;
    let radius = 0.6; // 0.3 object units times the scale 2
    let mut rng = Pcg32::new(77, 1);
    let mut cache = ();
    for _ in 0..4000 {
        let p = centre + DVec3::new(rng.next_f64() - 0.5, rng.next_f64() - 0.5, rng.next_f64() - 0.5) * 3.0;
        let q = grid.point(p).unwrap();
        let exact = (p - centre).length() - radius;
        let inside = (linear.inverse() * (p - translation)).cmpge(DVec3::ZERO).all() && (linear.inverse() * (p - translation)).cmple(DVec3::ONE).all();
        if inside && exact.abs() < 0.2 {
            // Trilinear interpolation errs by at most h²/8 times the Hessian's trace, 2/|x| for
            // |x| − r (cells of h = 2/47), plus the f32 rounding.
            let h = 2.0 / 47.0;
            let tolerance = h * h / 8.0 * 2.0 / (p - centre).length() * 1.05 + 1e-6;
            assert!((q.f - exact).abs() < tolerance, "f({p}) = {} vs {exact} (tolerance {tolerance})", q.f);
            if exact.abs() < 0.1 {
                assert!(q.normal.dot((p - centre).normalize()) > 0.99, "normal {}", q.normal);
            }
        }
        let d = DVec3::new(rng.next_f64() - 0.5, rng.next_f64() - 0.5, rng.next_f64() - 0.5).normalize();
        let length = 0.5 * rng.next_f64() + 1e-3;
        let b = grid.bound(&q, p, d, length, 0.01, &mut cache).unwrap();
        for j in 0..=20 {
            let s = b.length * j as f64 / 20.0;
            let f = grid.point(p + s * d).unwrap().f;
            let (lo, hi) = (b.lower_line(), b.upper_line());
            assert!(f >= lo.0 + lo.1 * s - 1e-9 && f <= hi.0 + hi.1 * s + 1e-9, "f = {f} outside the bound at s = {s}");
        }
    }
    let m = medium(Ndf::Gpss(Gpss::new(0.4, 0.4, 0.4).unwrap()), 0.03);
    let cases: Vec<Case> = sphere_cases(radius, 0.03).into_iter().map(|c| Case { origin: c.origin + centre, ..c }).collect();
    let alpha = sidak_alpha(0.01, 3 * cases.len());
    let (failures, stats) = check_surface("sdf grid", &m, &grid, &cases, 1500, alpha, 91);
    assert_eq!(stats.majorant_violations, 0);
    assert_eq!(failures, 0);
}

#[test]
fn sdf_grids_that_are_not_distances_are_refused() {
    use macrofacet::surface::GridSurface;
    let ones = vec![1.0f32; 27];
    let mut hole = ones.clone();
    hole[13] = -1.0; // the centre: a valid surface
    assert!(GridSurface::new(&hole, [3, 3, 3], glam::DMat3::IDENTITY, DVec3::ZERO).is_ok());
    let cases: [(&str, Vec<f32>, [usize; 3], glam::DMat3); 7] = [
        ("dimensions", hole.clone(), [1, 3, 9], glam::DMat3::IDENTITY),
        ("values for dimensions", hole.clone(), [3, 3, 2], glam::DMat3::IDENTITY),
        ("not finite", { let mut v = hole.clone(); v[4] = f32::NAN; v }, [3, 3, 3], glam::DMat3::IDENTITY),
        ("boundary", { let mut v = hole.clone(); v[0] = -0.5; v }, [3, 3, 3], glam::DMat3::IDENTITY),
        // fuzz/corpus/tracking/4e10ea34…: a sample of 1e30 (a "far" sentinel) made every call
        // near it run 65,536 segments and fail; the grid is refused instead, naming the cell.
        ("in cell (1, 1, 1)", { let mut v = hole.clone(); v[26] = 1e30; v }, [3, 3, 3], glam::DMat3::IDENTITY),
        ("uniform scale", hole.clone(), [3, 3, 3], glam::DMat3::from_diagonal(DVec3::new(1.0, 2.0, 1.0))),
        ("uniform scale", hole.clone(), [3, 3, 3], glam::DMat3::from_diagonal(DVec3::new(1.0, 1.0, -1.0))),
    ];
    for (needle, values, dims, linear) in cases {
        let e = GridSurface::new(&values, dims, linear, DVec3::ZERO).unwrap_err();
        assert!(e.message.contains(needle), "{needle}: {}", e.message);
    }
}

/// The exact projected-area bounds of isotropic gpss, Beckmann and GGX media
/// (`Ndf::projected_area_bound`, no Lipschitz margin) hold at every tentative collision: 100,000
/// rays per medium from random points of a sphere's shell in random directions, free flights
/// (majorant) and transmittance (majorant and control); gpss from height field to volume-like
/// with α_z below, equal to and above α, GGX up to α = 1 (and beyond, where the Lipschitz bound
/// takes over).
#[test]
fn closed_form_area_bounds_hold_for_random_rays_around_a_sphere() {
    let sphere = Sphere::new(DVec3::ZERO, 1.0, false, DVec3::Z).unwrap();
    let gpss = |a: f64, az: f64| Ndf::Gpss(Gpss::new(a, a, az).unwrap());
    let cases = [
        (0.005, gpss(0.1, 0.1)),
        (0.02, gpss(0.4, 0.4)),
        (0.005, gpss(0.1, 0.0)),
        (0.05, gpss(1.0, 1.0)),
        (0.02, gpss(0.4, 0.2)),
        (0.02, gpss(0.2, 0.8)),
        (0.01, Ndf::Beckmann(Beckmann::new(0.3, 0.3).unwrap())),
        (0.01, Ndf::Beckmann(Beckmann::new(2.0, 2.0).unwrap())),
        (0.01, Ndf::Ggx(macrofacet::ndf::Ggx::new(0.2, 0.2).unwrap())),
        (0.01, Ndf::Ggx(macrofacet::ndf::Ggx::new(1.0, 1.0).unwrap())),
        (0.01, Ndf::Ggx(macrofacet::ndf::Ggx::new(3.0, 3.0).unwrap())),
    ];
    for (sigma, ndf) in cases {
        let m = medium(ndf, sigma);
        let tracker = Tracker::new(&m, &sphere);
        let mut stats = TrackStats::default();
        let mut rng = Pcg32::new(5, 0);
        let mut unit = || loop {
            let v = DVec3::new(2.0 * rng.next_f64() - 1.0, 2.0 * rng.next_f64() - 1.0, 2.0 * rng.next_f64() - 1.0);
            if v.length() > 0.1 && v.length() < 1.0 {
                break v.normalize();
            }
        };
        for i in 0..100_000 {
            // From 5σ inside to 3σ above the mean surface (the shell's top).
            let p = unit() * (1.0 + sigma * (8.0 * (i as f64 + 0.5) / 100_000.0 - 5.0));
            let d = unit();
            let mut r = Pcg32::new(i, 1);
            tracker.sample_free_flight(p, d, 10.0, &mut r, &mut stats).unwrap();
            tracker.transmittance(p, d, 10.0, &mut r, &mut stats).unwrap();
        }
        assert!(stats.tentative_collisions > 50_000);
        assert_eq!(stats.majorant_violations, 0, "sigma {sigma}, {ndf:?}: {stats:?}");
    }
}

#[test]
fn bounds_built_once_track_as_the_trackers_own() {
    // A host builds a medium's projected-area bounds once (Tracker::with_bounds), with cells of
    // d·n that answer most segments' S_up and S_lo without evaluating an area (within 10 % of
    // the tracker's own bounds, which the library's unit test checks): the same free flights
    // and transmittances in distribution, no majorant violated. Bounds of another distribution
    // are not used: a rough one's would change the majorant (the other way round, break it).
    use macrofacet::tracking::ProjectedAreaBounds;
    let sphere = Sphere::new(DVec3::ZERO, 1.0, false, DVec3::Z).unwrap();
    let smooth = medium(Ndf::Beckmann(Beckmann::new(0.1, 0.1).unwrap()), 0.01);
    let rough = medium(Ndf::Gpss(Gpss::new(1.0, 1.0, 1.0).unwrap()), 0.01);
    let (own, foreign) = (ProjectedAreaBounds::of(&smooth), ProjectedAreaBounds::of(&rough));
    let fresh = Tracker::new(&smooth, &sphere);
    let (shared, mismatched) = (Tracker::with_bounds(&smooth, &own, &sphere, &Constant), Tracker::with_bounds(&smooth, &foreign, &sphere, &Constant));
    let mut rng = Pcg32::new(21, 7);
    // Per tracker: scattered-flight distances and transmittances.
    let (mut fresh_runs, mut shared_runs) = ((Vec::new(), Vec::new()), (Vec::new(), Vec::new()));
    for i in 0..2000u64 {
        // Rays from above toward the sphere's upper half, many grazing, and half of them on
        // their way out from inside the shell (as after a scattering event).
        let o = DVec3::new(rng.next_f64() - 0.5, rng.next_f64() - 0.5, 3.0);
        let d = (DVec3::new(rng.next_f64() - 0.5, rng.next_f64() - 0.5, 0.0) - o).normalize();
        let (o, d) = if i % 2 == 0 { (o, d) } else { (DVec3::new(o.x, o.y, 0.0).normalize() * 1.005, (d + 2.0 * DVec3::new(o.x, o.y, 1.0).normalize()).normalize()) };
        let run = |tracker: &Tracker<Sphere>| {
            let mut stats = TrackStats::default();
            let flight = tracker.sample_free_flight(o, d, 10.0, &mut Pcg32::new(i, 1), &mut stats).unwrap();
            let transmittance = tracker.transmittance(o, d, 10.0, &mut Pcg32::new(i, 2), &mut stats).unwrap();
            (flight, transmittance, stats)
        };
        let expected = run(&fresh);
        assert_eq!(run(&mismatched), expected, "ray {i}: another distribution's bounds were used");
        let got = run(&shared);
        assert_eq!(got.2.majorant_violations, 0, "ray {i}: {:?}", got.2);
        for ((flight, transmittance, _), runs) in [(expected, &mut fresh_runs), (got, &mut shared_runs)] {
            if let TrackedFlight::Scatter { t, .. } = flight {
                runs.0.push(t);
            }
            runs.1.push(transmittance);
        }
    }
    let (fresh_t, shared_t) = (mean_and_standard_error(fresh_runs.1.into_iter()), mean_and_standard_error(shared_runs.1.into_iter()));
    assert!((fresh_t.0 - shared_t.0).abs() < 4.0 * fresh_t.1.hypot(shared_t.1), "transmittance {fresh_t:?} against {shared_t:?}");
    let (fresh_n, shared_n) = (fresh_runs.0.len(), shared_runs.0.len());
    let p = ks_two_sample(&mut fresh_runs.0, &mut shared_runs.0);
    assert!(p > 1e-3, "free-flight distances differ: KS p = {p} ({fresh_n} and {shared_n} collisions)");
}

/// `τ` from `o` to `o + t_end d` by Gauss–Legendre panels of `σ/20` of the tracker's exact `σ_t`.
fn optical_depth_to<S: MeanSurface>(tracker: &Tracker<S>, surface: &S, sigma: f64, o: DVec3, d: DVec3, t_end: f64) -> f64 {
    let panels = (t_end / (sigma / 20.0)).ceil() as usize;
    let h = t_end / panels as f64;
    let nodes = common::gauss_legendre(4);
    (0..panels)
        .map(|i| {
            let t = i as f64 * h;
            nodes.iter().map(|&(x, w)| {
                let p = o + (t + 0.5 * h * (1.0 + x)) * d;
                0.5 * h * w * tracker.sigma_t_at(p, &surface.point(p).unwrap(), d).unwrap().0
            }).sum::<f64>()
        })
        .sum()
}

/// Thin shells of three distributions and a fuzzy one: the media of the opaque core's tests.
fn core_media() -> [(&'static str, MacrofacetMedium); 4] {
    [
        ("thin Beckmann", medium(Ndf::Beckmann(Beckmann { alpha_u: 0.3, alpha_v: 0.3 }), 1e-3)),
        ("thin anisotropic Beckmann", medium(Ndf::Beckmann(Beckmann { alpha_u: 0.05, alpha_v: 0.4 }), 1e-3)),
        ("thin GGX", medium(Ndf::Ggx(macrofacet::ndf::Ggx::new(0.1, 0.1).unwrap()), 1e-3)),
        ("fuzzy gpss", medium(Ndf::Gpss(Gpss { alpha_x: 0.5, alpha_y: 0.5, alpha_z: 0.5 }), 0.02)),
    ]
}

/// The opaque core (`macrofacet::opaque_core`): from the start level and from above the shell, at
/// angles from the radial ray down to rays that barely reach the core, the exact optical depth
/// to the core's first point is at least `OPAQUE_DEPTH` (the radial ray's little more: the
/// bound is tight there), and every transmittance estimate is 0. A mesh's core (its frame normals
/// are not the gradient) is never shallower; a varying field has none.
#[test]
fn an_opaque_core_is_opaque() {
    use macrofacet::opaque_core::{OPAQUE_DEPTH, START_SIGMAS};
    let sphere = Sphere::new(DVec3::ZERO, 1.0, false, DVec3::Z).unwrap();
    let octahedron = TriangleMesh::new(
        &[DVec3::X, -DVec3::X, DVec3::Y, -DVec3::Y, DVec3::Z, -DVec3::Z],
        &[[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]],
        None,
        None::<&[DVec2]>,
        1,
        f64::INFINITY,
    )
    .unwrap();
    let media = core_media();
    for (label, m) in &media {
        let tracker = Tracker::new(m, &sphere);
        let core = tracker.opaque_core().unwrap();
        let sigma = m.height.sigma;
        assert_eq!(core.start_level, -START_SIGMAS * sigma);
        let r_core = 1.0 + core.core_level;
        assert!(r_core > 0.0 && core.core_level < -30.0 * sigma, "{label}: core at {}", core.core_level);
        for f0 in [core.start_level, m.height.top()] {
            let r0 = 1.0 + f0;
            let grazing = (r_core / r0).acos();
            for k in 1..=4 {
                let beta = grazing + k as f64 * (0.5 * std::f64::consts::PI - grazing) / 4.0;
                let (o, d) = (DVec3::new(0.0, 0.0, r0), DVec3::new(beta.cos(), 0.0, -beta.sin()));
                let b = o.dot(d);
                let t_core = -b - (b * b - (r0 * r0 - r_core * r_core)).sqrt();
                let tau = optical_depth_to(&tracker, &sphere, sigma, o, d, t_core);
                assert!(tau >= OPAQUE_DEPTH * (1.0 - 1e-6), "{label}: from f = {f0}, {beta} below the tangent: tau = {tau}");
                if k == 4 && f0 == core.start_level {
                    assert!(tau <= 1.1 * OPAQUE_DEPTH, "{label}: the radial ray's depth {tau} (the bound is loose)");
                }
                for seed in 0..16 {
                    let t = tracker.transmittance(o, d, f64::INFINITY, &mut Pcg32::new(seed, 7), &mut TrackStats::default()).unwrap();
                    assert_eq!(t, 0.0, "{label}: seed {seed}, {beta} below the tangent");
                }
            }
        }
        if let Some(mesh_core) = Tracker::new(m, &octahedron).opaque_core() {
            assert!(mesh_core.core_level <= core.core_level, "{label}: the mesh's core {mesh_core:?} above the sphere's {core:?}");
        }
        let field = TestField { sigma: [0.5 * sigma, sigma], alpha: [0.3, 0.3], anisotropy: None, understate: false };
        assert_eq!(Tracker::with_field(m, &sphere, &field).opaque_core(), None, "{label}: a varying field");
    }
}

/// The depth roulette's bound (`macrofacet::opaque_core::descent_transmittance_bound`) on spheres
/// of radius 10σ to 1000σ: from heights across the shell (and above it), at angles from
/// grazing to radial, the exact transmittance to the chord's deepest point (and to its end,
/// past which a ray only climbs) is at most the bound, and within a few times it on the radial ray
/// (the bound is tight there).
#[test]
fn the_depth_roulettes_bound_holds() {
    use macrofacet::opaque_core::descent_transmittance_bound;
    let media = core_media();
    for (label, m) in &media {
        let sigma = m.height.sigma;
        for r in [10.0 * sigma, 100.0 * sigma, 1000.0 * sigma] {
            let sphere = Sphere::new(DVec3::ZERO, r, false, DVec3::Z).unwrap();
            let tracker = Tracker::new(m, &sphere);
            let kappa = tracker.descent_rate().unwrap();
            assert!(kappa > 0.5 && kappa <= 1.0, "{label}: rate {kappa}");
            for f0 in [-3.0 * sigma, 0.0, 1.5 * sigma, m.height.top() + sigma] {
                let o = DVec3::new(0.0, 0.0, r + f0);
                // 1.5707963 kept as written (just short of horizontal): π/2 would change the input.
                #[allow(clippy::approx_constant)]
                for beta in [0.02, 0.1, 0.3, 0.7, 1.5707963] {
                    let d = DVec3::new(f64::cos(beta), 0.0, -f64::sin(beta));
                    let s = -o.dot(d);
                    let f_deepest = (o + s * d).length() - r;
                    let bound = descent_transmittance_bound(&m.height, kappa, f0, f_deepest);
                    for t_end in [s, 2.0 * s] {
                        let exact = (-optical_depth_to(&tracker, &sphere, sigma, o, d, t_end)).exp();
                        assert!(exact <= bound * (1.0 + 1e-6), "{label}, r = {r}: from f = {f0} at {beta} below the tangent to t = {t_end}: T = {exact:e} > bound {bound:e}");
                        if beta > 1.5 && f0 == 0.0 && t_end == s && bound > 1e-300 {
                            assert!(exact >= bound.powf(1.0 / kappa) * 1e-3, "{label}, r = {r}: the radial T = {exact:e} far below the bound {bound:e}");
                        }
                    }
                }
            }
        }
    }
}

/// A caller's depth roulette (`Tracker::depth_roulette`, `Tracker::after_roulette`) keeps the
/// transmittance estimates unbiased: over rays that descend into a thin shell at a range of
/// depths, the mean of the roulette's estimates (0 for rays not kept) matches the exact
/// transmittance and the tracker's plain estimates, every kept estimate is at most
/// `1/survival`, and the roulette ends the deep rays without tracking them.
#[test]
fn a_depth_roulette_keeps_transmittance_unbiased() {
    use macrofacet::tracking::roulette_survival;
    let m = medium(Ndf::Beckmann(Beckmann { alpha_u: 0.3, alpha_v: 0.3 }), 1e-3);
    let sigma = m.height.sigma;
    let r = 100.0 * sigma;
    let sphere = Sphere::new(DVec3::ZERO, r, false, DVec3::Z).unwrap();
    let tracker = Tracker::new(&m, &sphere);
    let mut rng = Pcg32::new(2026, 12);
    let n = 20_000;
    let mut killed = 0;
    for beta in [0.01, 0.05, 0.12, 0.18, 0.22, 0.3] {
        let o = DVec3::new(0.0, 0.0, r);
        let d = DVec3::new(f64::cos(beta), 0.0, -f64::sin(beta));
        let s = -o.dot(d);
        let f_deepest = (o + s * d).length() - r;
        let exact = (-optical_depth_to(&tracker, &sphere, sigma, o, d, 2.0 * s)).exp();
        let (mut roulette, mut plain) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for _ in 0..n {
            let survival = tracker.depth_roulette(0.0, f_deepest, rng.next_f64()).unwrap();
            assert!(survival == 0.0 || (survival > 0.0 && survival <= 1.0), "survival {survival}");
            roulette.push(if survival > 0.0 {
                let kept = Tracker::new(&m, &sphere).after_roulette(survival).unwrap();
                let t = kept.transmittance(o, d, 2.0 * s, &mut rng, &mut TrackStats::default()).unwrap();
                assert!((0.0..=1.0 / survival).contains(&t), "estimate {t} kept with {survival}");
                t
            } else {
                killed += 1;
                0.0
            });
            plain.push(tracker.transmittance(o, d, 2.0 * s, &mut rng, &mut TrackStats::default()).unwrap());
        }
        let (a, b) = (mean_and_standard_error(roulette.into_iter()), mean_and_standard_error(plain.into_iter()));
        // (Estimates near 0.5 once a roulette has played: a standard error of at least
        // sqrt(T/2n) even where no sample happened to be nonzero.)
        let tolerance = |se: f64| 4.0 * se.max((0.5 * exact / n as f64).sqrt());
        assert!((a.0 - exact).abs() <= tolerance(a.1), "{beta} below the tangent: roulette {a:?} against the exact {exact:e}");
        assert!((b.0 - exact).abs() <= tolerance(b.1), "{beta} below the tangent: plain {b:?} against the exact {exact:e}");
    }
    assert!(killed > n, "the roulette ended only {killed} rays");
    for bad in [0.0, -0.5, 1.5, f64::NAN, f64::INFINITY] {
        assert!(Tracker::new(&m, &sphere).after_roulette(bad).is_err(), "survival {bad} taken");
    }
    assert_eq!(roulette_survival(0.25), 0.5);
    assert_eq!(roulette_survival(0.9), 1.0);
    assert_eq!(roulette_survival(f64::NAN), 1.0);
}

#[test]
fn hints_change_no_result() {
    // A collision's hint (TrackedFlight::Scatter) seeds the first query of the calls that start
    // there (Tracker::from_hint), and any value is safe. From collisions on a shaded torus and a
    // flat cube, escape flights and shadow rays with the collision's own hint, a foreign
    // triangle's, one past the last triangle and u64::MAX agree with those without (same seeds).
    let m = medium(Ndf::Beckmann(Beckmann::new(0.3, 0.3).unwrap()), 1e-3);
    for (name, mesh) in [("torus", meshes::torus(1.0, 0.4, 48, 24)), ("cube", meshes::cube())] {
        let surface = mesh_surface(&mesh);
        let n = mesh.indices.len() as u64;
        let plain = Tracker::new(&m, &surface);
        let (mut collisions, mut hinted) = (0, 0);
        let mut rng = Pcg32::new(41, 5);
        let mut stats = TrackStats::default();
        for i in 0..400u64 {
            let o = 3.0 * common::spherical((2.0 * rng.next_f64() - 1.0).acos(), 2.0 * std::f64::consts::PI * rng.next_f64());
            let aim = DVec3::new(rng.next_f64() - 0.5, rng.next_f64() - 0.5, 0.2 * (rng.next_f64() - 0.5));
            let d = (aim - o).normalize();
            let TrackedFlight::Scatter { t, hint, .. } = plain.sample_free_flight(o, d, f64::INFINITY, &mut Pcg32::new(i, 1), &mut stats).unwrap() else { continue };
            collisions += 1;
            hinted += usize::from(hint != 0);
            let p = o + t * d;
            // Half the directions leave the surface, half enter it.
            let w = common::spherical((2.0 * rng.next_f64() - 1.0).acos(), 2.0 * std::f64::consts::PI * rng.next_f64());
            for h in [hint, (hint + 17) % n + 1, n + 1, u64::MAX] {
                let hinted_tracker = Tracker::new(&m, &surface).from_hint(h);
                let a = plain.sample_free_flight(p, w, f64::INFINITY, &mut Pcg32::new(i, 2), &mut stats).unwrap();
                let b = hinted_tracker.sample_free_flight(p, w, f64::INFINITY, &mut Pcg32::new(i, 2), &mut stats).unwrap();
                match (a, b) {
                    (TrackedFlight::Scatter { t: ta, point: pa, .. }, TrackedFlight::Scatter { t: tb, point: pb, .. }) => {
                        assert!((ta - tb).abs() <= 1e-9 * ta.max(1e-3), "{name} ray {i}, hint {h}: {ta} vs {tb}");
                        assert!((pa.normal - pb.normal).length() <= 1e-9, "{name} ray {i}, hint {h}: {pa:?} vs {pb:?}");
                    }
                    (TrackedFlight::Pass, TrackedFlight::Pass) => {}
                    other => panic!("{name} ray {i}, hint {h}: {other:?}"),
                }
                let ta = plain.transmittance(p, w, f64::INFINITY, &mut Pcg32::new(i, 3), &mut stats).unwrap();
                let tb = hinted_tracker.transmittance(p, w, f64::INFINITY, &mut Pcg32::new(i, 3), &mut stats).unwrap();
                assert!((ta - tb).abs() <= 1e-9 * ta.max(1.0), "{name} ray {i}, hint {h}: transmittance {ta} vs {tb}");
            }
        }
        // Most collisions lie in a triangle's certified region, and hand it on.
        assert!(collisions >= 200 && 10 * hinted >= 9 * collisions, "{name}: {hinted} of {collisions} collisions hinted");
    }
}
