//! Throughput of the core queries a renderer calls per event. Prints nanoseconds per call.
//!
//!     cargo run --release --example bench_core
//!
//! Inputs are drawn once, before timing, from a fixed seed; each figure is the best of five
//! passes over the same inputs (to discount start-up noise on a shared machine).

use glam::DVec3;
use macrofacet::ndf::{Beckmann, Ggx, Gpss, MicrofacetDistribution, Ndf};
use macrofacet::stats::Pcg32;
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
    let mut rng = Pcg32::new(1, 1);
    let dirs: Vec<DVec3> = (0..N).map(|_| uniform_direction(&mut rng)).collect();
    let us: Vec<[f64; PHASE_SAMPLE_DIMENSIONS]> = (0..N).map(|_| std::array::from_fn(|_| rng.next_f64())).collect();
    let fs: Vec<f64> = (0..N).map(|_| 6.0 * rng.next_f64() - 4.0).collect();

    let ndfs = [
        ("beckmann", Ndf::Beckmann(Beckmann::new(0.3, 0.5).unwrap())),
        ("ggx", Ndf::Ggx(Ggx::new(0.3, 0.5).unwrap())),
        ("gpss", Ndf::Gpss(Gpss::new(0.5, 0.5, 0.5).unwrap())),
    ];
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
}
