//! Appendix: checks of the independent reference implementations themselves (so that an
//! agreement in sections 3–4 is not two copies of one mistake, and a disagreement can be
//! attributed).

use crate::reference::{fresnel, heitz_walk, normal_cdf, probit, single_scattering_albedo, Dist};
use crate::util::{md_table, par_map, yes_no, Ctx, Section};
use glam::DVec3;
use macrofacet::frame::Frame;
use macrofacet::fresnel::{fresnel_conductor, CONDUCTOR_PRESETS};
use macrofacet_validation::stats::{sidak_alpha, Pcg32, SphereChi2};
use std::fmt::Write as _;

const SEED: u64 = 9_000;

pub fn run(ctx: &Ctx) -> Section {
    let mut md = String::new();
    let mut summary_ok = true;
    let _ = writeln!(md, "Checks of the reference code in `examples/validate/reference.rs` (written without the library's maths).\n");

    // Fresnel: complex-arithmetic form vs the library's closed form.
    let mut worst_f: f64 = 0.0;
    for p in CONDUCTOR_PRESETS {
        for c in 0..3 {
            for i in 0..=1000 {
                let cos = i as f64 / 1000.0;
                worst_f = worst_f.max((fresnel(cos, p.eta[c], p.k[c]) - fresnel_conductor(cos, p.eta[c], p.k[c])).abs());
            }
        }
    }
    // probit: relative round-trip error.
    let mut worst_p: f64 = 0.0;
    for i in 1..2000 {
        for p in [i as f64 / 2000.0, (-(i as f64) / 40.0).exp()] {
            let back = normal_cdf(probit(p));
            worst_p = worst_p.max(((back - p) / p.min(1.0 - p)).abs());
        }
    }
    let ok_fp = worst_f < 1e-10 && worst_p < 1e-10;
    summary_ok &= ok_fp;
    let _ = writeln!(
        md,
        "- Conductor Fresnel by complex Snell/Fresnel amplitudes vs the library's closed form (all presets, channels, \
         1001 cosines): max |Δ| = {worst_f:.1e}. Inverse normal cdf round trip: max relative error {worst_p:.1e}. {}\n",
        if ok_fp { "OK." } else { "**MISMATCH.**" }
    );

    // Visible-normal samplers of the reference walk: chi-square against <wi, m> D(m) / area.
    let dists = [Dist::Beckmann(0.3), Dist::Beckmann(1.0), Dist::Ggx(0.3), Dist::Ggx(1.0)];
    let thetas = [0.0, 45.0, 80.0, 110.0, 135.0];
    let samples = if ctx.quick { 20_000 } else { 200_000 };
    let jobs: Vec<(usize, usize)> = (0..dists.len()).flat_map(|d| (0..thetas.len()).map(move |t| (d, t))).collect();
    let level = sidak_alpha(0.01, jobs.len());
    let outcomes = par_map(&jobs, ctx.threads, |&(d, t)| {
        let dist = dists[d];
        let th = f64::to_radians(thetas[t]);
        let wi = DVec3::new(th.sin(), 0.0, th.cos());
        let area = dist.projected_area(wi);
        let test = SphereChi2 { theta_bins: 16, phi_bins: 32, samples, quadrature: 8, min_expected: 5.0 };
        let mut rng = Pcg32::new(SEED + 10 * d as u64 + t as u64, 0);
        // Bin around wi for Beckmann (the kink of <wi, m> lies on a bin edge, D is smooth at
        // m_z = 0); keep the standard frame for GGX, whose D jumps at m_z = 0 (a bin edge there).
        let frame = match dist {
            Dist::Beckmann(_) => Frame::from_normal_tangent(wi, DVec3::Y).unwrap(),
            Dist::Ggx(_) => Frame::identity(),
        };
        test.run(
            |ml| {
                let m = frame.to_world(ml);
                if m.z > 0.0 { wi.dot(m).max(0.0) * dist.d(m) / area } else { 0.0 }
            },
            |r| dist.sample_vndf(wi, r).map(|m| frame.to_local(m)),
            &mut rng,
        )
    });
    let mut rows = Vec::new();
    let mut ok_v = true;
    for (&(d, t), o) in jobs.iter().zip(&outcomes) {
        let ok = o.passes(level) && (o.pdf_integral - 1.0).abs() < 1e-3;
        ok_v &= ok;
        rows.push(vec![format!("{} α = {}", dists[d].name(), dists[d].alpha()), format!("{:.0}°", thetas[t]), format!("{:.3}", o.p_value), format!("{:.5}", o.pdf_integral), yes_no(ok)]);
    }
    summary_ok &= ok_v;
    let _ = writeln!(
        md,
        "- Reference visible-normal samplers (Beckmann by visible slopes, GGX by Heitz 2018), {samples} samples each, \
         Pearson χ² on 16 × 32 sphere cells against `<wi, m> D(m) / ((1 + Λ(wi)) cos θi)` (library `stats::SphereChi2`), \
         including directions from below the horizon (110°, 135°), which the walk needs after upward reflections. \
         Šidák level {level:.1e} per test (1 % overall).\n\n{}",
        md_table(&["distribution", "θ of wi", "p-value", "∫ pdf", "passes"], &rows)
    );

    // Albedo quadrature convergence.
    let g = macrofacet::fresnel::conductor_preset("Au").unwrap();
    let qjobs: Vec<(Dist, f64)> = [Dist::Beckmann(0.1), Dist::Ggx(0.1), Dist::Beckmann(1.0), Dist::Ggx(1.0)]
        .into_iter()
        .flat_map(|d| [0.0f64, 60.0, 85.0].into_iter().map(move |t| (d, t)))
        .collect();
    let worst_q = par_map(&qjobs, ctx.threads, |&(dist, th)| {
        let a = single_scattering_albedo(&dist, g.eta, g.k, th.to_radians(), 96);
        let b = single_scattering_albedo(&dist, g.eta, g.k, th.to_radians(), 192);
        (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f64::max)
    })
    .into_iter()
    .fold(0.0, f64::max);
    let ok_q = worst_q < 1e-4;
    summary_ok &= ok_q;
    let _ = writeln!(
        md,
        "- Analytic single-scattering albedo quadrature, 96 vs 192 panels (α = 0.1 and 1, θ = 0°, 60°, 85°, gold): max \
         |Δ| = {worst_q:.1e}. {}\n",
        if ok_q { "OK." } else { "**not converged.**" }
    );

    // White furnace of the Heitz walk: a perfect conductor (η = 0) reflects everything.
    let n = if ctx.quick { 20_000 } else { 200_000 };
    let mut frows = Vec::new();
    let mut ok_w = true;
    for dist in [Dist::Beckmann(1.0), Dist::Ggx(1.0)] {
        for th in [0.0f64, 80.0] {
            let wi = DVec3::new(th.to_radians().sin(), 0.0, th.to_radians().cos());
            let mut rng = Pcg32::new(SEED + 500, th as u64);
            let (mut e, mut orders, mut lost) = (0.0, 0.0, 0usize);
            for _ in 0..n {
                let p = heitz_walk(&dist, [0.0; 3], [1.0; 3], wi, 10_000, &mut rng);
                e += p.energy[0];
                orders += p.order as f64;
                if p.energy[0] == 0.0 {
                    lost += 1;
                }
            }
            let ok = lost == 0 && (e / n as f64 - 1.0).abs() < 1e-9;
            ok_w &= ok;
            frows.push(vec![format!("{} α = {}", dist.name(), dist.alpha()), format!("{th:.0}°"), format!("{:.12}", e / n as f64), format!("{:.3}", orders / n as f64), format!("{lost}"), yes_no(ok)]);
        }
    }
    summary_ok &= ok_w;
    let _ = writeln!(
        md,
        "- White furnace of the reference Heitz 2016 walk (perfect conductor, {n} paths):\n\n{}",
        md_table(&["distribution", "θi", "albedo", "mean order", "lost paths", "passes"], &frows)
    );
    Section {
        title: "Appendix A. Checks of the independent references".into(),
        markdown: md,
        summary: vec![("A. Reference self-checks (Fresnel, probit, vNDF samplers, quadrature, furnace)".into(), if summary_ok { "all pass".into() } else { "see appendix".into() }, yes_no(summary_ok))],
        seconds: 0.0,
    }
}
