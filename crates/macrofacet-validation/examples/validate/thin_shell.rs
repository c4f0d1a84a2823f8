//! Comparison 3: the thin shell (a semi-infinite macrofacet slab) vs microfacet theory
//! (seeds/000 Figs. 13–14): single scattering vs the analytic BRDF, all orders vs an independent
//! Heitz et al. 2016 random walk.

use crate::plot::{Figure, LegendPos, Panel, Series, BLACK, GRAY, PALETTE};
use crate::reference::{heitz_nee, heitz_walk, single_scattering_albedo, single_scattering_density, Dist};
use crate::util::{md_table, par_map, yes_no, Acc3, Ctx, Section};
use glam::DVec3;
use macrofacet::fresnel::conductor_preset;
use macrofacet::height::HeightProfile;
use macrofacet::medium::FreeFlight;
use macrofacet::ndf::{Beckmann, Ggx, Ndf};
use macrofacet_validation::slab::{random_walk, walk_from, WalkOutcome};
use macrofacet_validation::stats::Pcg32;
use macrofacet::{MacrofacetMedium, MacrofacetPhase, MicroBsdf, VndfSampling, PHASE_SAMPLE_DIMENSIONS};
use std::fmt::Write as _;

const SEED: u64 = 3_000;
const SIGMA: f64 = 0.01;
const SHELL_EXTENT: f64 = 8.0;
const MAX_ORDER: u32 = 10_000;
/// Largest |z| accepted: Šidák over the (config, angle, channel) comparisons at 1 % overall
/// is ≈ 4.3 for a few hundred comparisons; 4.5 leaves room.
const Z_TOL: f64 = 4.5;

fn gold() -> ([f64; 3], [f64; 3]) {
    let g = conductor_preset("Au").unwrap();
    (g.eta, g.k)
}

fn library_ndf(dist: &Dist) -> Ndf {
    match *dist {
        Dist::Beckmann(a) => Ndf::Beckmann(Beckmann::new(a, a).unwrap()),
        Dist::Ggx(a) => Ndf::Ggx(Ggx::new(a, a).unwrap()),
    }
}

fn medium(dist: &Dist) -> MacrofacetMedium {
    let (eta, k) = gold();
    MacrofacetMedium {
        height: HeightProfile::new(SIGMA, SHELL_EXTENT).unwrap(),
        phase: MacrofacetPhase { ndf: library_ndf(dist), micro_bsdf: MicroBsdf::Conductor { eta, k, specular_reflectance: [1.0; 3] }, sampling: VndfSampling::Exact },
    }
}

fn incident(theta_deg: f64) -> DVec3 {
    let t = theta_deg.to_radians();
    DVec3::new(t.sin(), 0.0, t.cos())
}

#[derive(Clone, Copy)]
enum Kind {
    /// Macrofacet single scattering: first collision, phase sample, `T` to the top along it.
    MacroSingle,
    /// Macrofacet slab walk, all orders.
    MacroAll,
    /// Heitz 2016 walk (all orders, and its single-bounce part).
    Heitz,
    /// Analytic single-scattering albedo by quadrature.
    Analytic,
}

struct Job {
    dist: usize,
    angle: usize,
    kind: Kind,
    chunk: u64,
    n: usize,
}

/// One result: the estimator's accumulator (for Heitz also the single-bounce part), or the
/// quadrature value.
struct Res {
    acc: Acc3,
    acc_single: Acc3,
    exact: [f64; 3],
}

pub fn run(ctx: &Ctx) -> Section {
    let (eta, k) = gold();
    let alphas = [0.1, 0.3, 0.6, 1.0];
    let dists: Vec<Dist> = alphas.iter().map(|&a| Dist::Beckmann(a)).chain(alphas.iter().map(|&a| Dist::Ggx(a))).collect();
    let angles: Vec<f64> = if ctx.quick { vec![0.0, 30.0, 60.0, 75.0, 85.0] } else { (0..18).map(|i| 5.0 * i as f64).collect() };
    let (n, chunks, panels) = if ctx.quick { (20_000, 1, 48) } else { (400_000, 4, 96) };
    let mut jobs = Vec::new();
    for d in 0..dists.len() {
        for a in 0..angles.len() {
            jobs.push(Job { dist: d, angle: a, kind: Kind::Analytic, chunk: 0, n: 0 });
            for kind in [Kind::MacroSingle, Kind::MacroAll, Kind::Heitz] {
                for c in 0..chunks {
                    jobs.push(Job { dist: d, angle: a, kind, chunk: c as u64, n: n / chunks });
                }
            }
        }
    }
    let results = par_map(&jobs, ctx.threads, |job| {
        let dist = &dists[job.dist];
        let theta = angles[job.angle];
        let wi = incident(theta);
        let m = medium(dist);
        let kind_index = match job.kind {
            Kind::MacroSingle => 0,
            Kind::MacroAll => 1,
            Kind::Heitz => 2,
            Kind::Analytic => 3,
        };
        let mut rng = Pcg32::new(SEED + 1000 * kind_index + 100 * job.dist as u64 + job.angle as u64, job.chunk);
        let mut res = Res { acc: Acc3::default(), acc_single: Acc3::default(), exact: [0.0; 3] };
        match job.kind {
            Kind::Analytic => res.exact = single_scattering_albedo(dist, eta, k, theta.to_radians(), panels),
            Kind::MacroSingle => {
                for _ in 0..job.n {
                    let mut v = [0.0; 3];
                    if let FreeFlight::Scatter { t } = m.sample_free_flight(m.height.top(), -wi, f64::INFINITY, rng.next_f64()) {
                        let f = m.height.top() - t * wi.z;
                        let u: [f64; PHASE_SAMPLE_DIMENSIONS] = std::array::from_fn(|_| rng.next_f64());
                        if let Some(s) = m.phase.sample(wi, u) {
                            let tr = m.transmittance(f, s.wo, f64::INFINITY);
                            v = s.weight.map(|w| w * tr);
                        }
                    }
                    res.acc.add(v);
                }
            }
            Kind::MacroAll => {
                for _ in 0..job.n {
                    let v = match random_walk(&m, wi, MAX_ORDER, || rng.next_f64()) {
                        WalkOutcome::Escaped { weight, .. } => weight,
                        _ => [0.0; 3],
                    };
                    res.acc.add(v);
                }
            }
            Kind::Heitz => {
                for _ in 0..job.n {
                    let p = heitz_walk(dist, eta, k, wi, MAX_ORDER, &mut rng);
                    res.acc.add(p.energy);
                    res.acc_single.add(if p.order == 1 { p.energy } else { [0.0; 3] });
                }
            }
        }
        res
    });
    // Gather per (dist, angle): [macro single, macro all, heitz all, heitz single], analytic.
    let mut table: Vec<Vec<([Acc3; 4], [f64; 3])>> = vec![vec![([Acc3::default(); 4], [0.0; 3]); angles.len()]; dists.len()];
    for (job, r) in jobs.iter().zip(&results) {
        let cell = &mut table[job.dist][job.angle];
        match job.kind {
            Kind::MacroSingle => cell.0[0].merge(&r.acc),
            Kind::MacroAll => cell.0[1].merge(&r.acc),
            Kind::Heitz => {
                cell.0[2].merge(&r.acc);
                cell.0[3].merge(&r.acc_single);
            }
            Kind::Analytic => cell.1 = r.exact,
        }
    }

    let mut md = String::new();
    let _ = writeln!(
        md,
        "A semi-infinite slab of gold conductor flakes (`material = Au`: η, k of the library's preset) with Gaussian \
         heights, σ = {SIGMA} (the paper's thin shell; the slab is scale-invariant, so σ does not matter), shell top at \
         +{SHELL_EXTENT}σ (a 3σ cut would drop the flakes above it, Φ(−3) = 1.3e-3 of the surface, and bias the \
         comparison), exact vNDF sampling. Light arrives from wi at θ = {} from the normal. Albedo = reflected \
         fraction of the incident power; plots show the channel average (R+G+B)/3, tables every channel.\n\n\
         - **Single scattering.** Macrofacet: collision estimator (first free flight from the top, one phase sample, \
         weight × T(f → top along wo), i.e. the albedo of single-event paths with the escape replaced by its \
         probability) vs the analytic microfacet BRDF `F D G₂ / (4 cos θi cos θo)` with Smith's height-correlated \
         `G₂ = 1/(1 + Λ(wi) + Λ(wo))`, integrated over the hemisphere by Gauss–Legendre quadrature in slope space \
         ({panels}×8 nodes per axis; Fresnel in independent complex arithmetic). **Expected:** equal within MC \
         error (seeds/002 §3: the semi-infinite microflake slab *is* the Smith microsurface, so this is exact for \
         any σ). The Heitz walk's single-bounce part is a third estimate of the same quantity.\n\
         - **All orders.** Macrofacet `slab::random_walk` vs an independent reimplementation of the Heitz, Hanika, \
         d'Eon, Dachsbacher 2016 microsurface walk (Gaussian heights, `sampleHeight` by inverting `C1 = Φ` with \
         Smith's Λ; Beckmann visible slopes after Heitz & d'Eon 2014, GGX visible normals after Heitz 2018), both \
         capped at {MAX_ORDER} events. **Expected:** equal within MC error (both simulate the same Smith \
         microsurface).\n\
         - Paths: N = {n} per (distribution, α, θ, estimator), in {chunks} chunks seeded `Pcg32::new({SEED} + 1000·estimator \
         + 100·config + angle index, chunk)`. Verdict: every |z| ≤ {Z_TOL} (z = difference / combined SE; Šidák for a few \
         hundred comparisons at 1 %). Each SE is floored at 1/N (one path of unit weight), so that a rare event \
         missing from the sample (a second bounce at low roughness) cannot make z spuriously large.\n",
        angles.iter().map(|a| format!("{a:.0}°")).collect::<Vec<_>>().join(", "),
    );
    let mut rows = Vec::new();
    let mut csv = Vec::new();
    let mut summary_single = (0.0f64, 0.0f64, true);
    let mut summary_all = (0.0f64, 0.0f64, true);
    let mut panels_out: Vec<Panel> = Vec::new();
    for (family, fam_name) in [(0usize, "Beckmann"), (1usize, "GGX")] {
        let mut p_single = Panel::new(&format!("{fam_name}: single scattering"), "θi (deg)", "albedo");
        let mut p_all = Panel::new(&format!("{fam_name}: all orders"), "θi (deg)", "albedo");
        let mut z_single = Panel::new(&format!("{fam_name}: single, z = Δ/SE"), "θi (deg)", "z");
        let mut z_all = Panel::new(&format!("{fam_name}: all orders, z = Δ/SE"), "θi (deg)", "z");
        for p in [&mut p_single, &mut p_all, &mut z_single, &mut z_all] {
            p.x = Some((0.0, 85.0));
        }
        for p in [&mut z_single, &mut z_all] {
            p.hlines.push((0.0, GRAY, false));
            p.hlines.push((3.0, GRAY, true));
            p.hlines.push((-3.0, GRAY, true));
            p.legend = LegendPos::None; // same colours as the albedo panels
        }
        p_single.legend = LegendPos::BottomLeft;
        p_all.legend = LegendPos::BottomLeft;
        for p in [&mut p_single, &mut p_all] {
            p.legend_room = 0.6;
        }
        for (ai, &alpha) in alphas.iter().enumerate() {
            let di = family * alphas.len() + ai;
            let dist = &dists[di];
            let color = PALETTE[ai];
            let mut worst_s = (0.0f64, 0.0f64, 0.0f64, 0usize, 0usize); // (|Δ|, se, z, angle, channel)
            let mut worst_a = (0.0f64, 0.0f64, 0.0f64, 0usize, 0usize);
            let mut worst_h = 0.0f64;
            let (mut ana, mut ms, mut ma, mut ha, mut zs, mut za) = (vec![], vec![], vec![], vec![], vec![], vec![]);
            for (a, &theta) in angles.iter().enumerate() {
                let (accs, exact) = &table[di][a];
                // SE floored at 1/N (one path of unit weight): a rare event absent from the
                // sample (e.g. a second bounce at α = 0.1, normal incidence) must not make the
                // sample SE, and hence z, spuriously small. Negligible at full sample counts.
                let se_floor = |a: &Acc3| a.se().map(|x| x.hypot(1.0 / a.n.max(1.0)));
                let (msm, mss) = (accs[0].mean(), se_floor(&accs[0]));
                let (mam, mas) = (accs[1].mean(), se_floor(&accs[1]));
                let (ham, has) = (accs[2].mean(), se_floor(&accs[2]));
                let (hsm, hss) = (accs[3].mean(), se_floor(&accs[3]));
                for c in 0..3 {
                    let ds = msm[c] - exact[c];
                    summary_single.0 = summary_single.0.max(ds.abs());
                    summary_all.0 = summary_all.0.max((mam[c] - ham[c]).abs());
                    let z = ds / mss[c].max(1e-300);
                    if z.abs() > worst_s.2.abs() {
                        worst_s = (ds, mss[c], z, a, c);
                    }
                    let da = mam[c] - ham[c];
                    let se = (mas[c] * mas[c] + has[c] * has[c]).sqrt();
                    let z = da / se.max(1e-300);
                    if z.abs() > worst_a.2.abs() {
                        worst_a = (da, se, z, a, c);
                    }
                    worst_h = worst_h.max(((hsm[c] - exact[c]) / hss[c].max(1e-300)).abs());
                }
                csv.push(format!(
                    "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                    dist.name(), alpha, theta,
                    exact[0], exact[1], exact[2],
                    msm[0], msm[1], msm[2], mss[0], mss[1], mss[2],
                    mam[0], mam[1], mam[2], mas[0], mas[1], mas[2],
                    ham[0], ham[1], ham[2], has[0], has[1], has[2],
                    hsm[0], hsm[1], hsm[2], hss[0], hss[1], hss[2]
                ));
                let grey = |v: [f64; 3]| (v[0] + v[1] + v[2]) / 3.0;
                let (gs, gss) = accs[0].grey();
                let (ga, gas) = accs[1].grey();
                let (gh, ghs) = accs[2].grey();
                ana.push((theta, grey(*exact)));
                ms.push((theta, gs));
                ma.push((theta, ga));
                ha.push((theta, gh));
                zs.push((theta, (gs - grey(*exact)) / gss.max(1e-300)));
                za.push((theta, (ga - gh) / (gas * gas + ghs * ghs).sqrt().max(1e-300)));
            }
            let label = format!("α = {alpha}");
            p_single.series.push(Series::line(&format!("{label} analytic"), color, ana));
            p_single.series.push(Series::markers("", color, ms, None));
            p_all.series.push(Series::line(&format!("{label} Heitz 2016"), color, ha));
            p_all.series.push(Series::markers("", color, ma, None));
            z_single.series.push(Series::markers(&label, color, zs, None));
            z_all.series.push(Series::markers(&label, color, za, None));
            let chan = ["R", "G", "B"];
            let ok_s = worst_s.2.abs() <= Z_TOL && worst_h <= Z_TOL;
            let ok_a = worst_a.2.abs() <= Z_TOL;
            summary_single.1 = summary_single.1.max(worst_s.2.abs());
            summary_single.2 &= ok_s;
            summary_all.1 = summary_all.1.max(worst_a.2.abs());
            summary_all.2 &= ok_a;
            let (a0, a_last) = (&table[di][0], &table[di][angles.len() - 1]);
            let ms_share = |cell: &([Acc3; 4], [f64; 3])| {
                let all = cell.0[2].grey().0;
                let single = (cell.1[0] + cell.1[1] + cell.1[2]) / 3.0;
                (all - single) / all
            };
            rows.push(vec![
                dist.name().to_string(),
                format!("{alpha}"),
                format!("{:+.2e} ± {:.1e} ({:+.1} SE; {}°, {})", worst_s.0, worst_s.1, worst_s.2, angles[worst_s.3], chan[worst_s.4]),
                format!("{worst_h:.1}"),
                format!("{:+.2e} ± {:.1e} ({:+.1} SE; {}°, {})", worst_a.0, worst_a.1, worst_a.2, angles[worst_a.3], chan[worst_a.4]),
                format!("{:.1} % / {:.1} %", 100.0 * ms_share(a0), 100.0 * ms_share(a_last)),
                yes_no(ok_s && ok_a),
            ]);
        }
        panels_out.push(p_single);
        panels_out.push(p_all);
        panels_out.push(z_single);
        panels_out.push(z_all);
    }
    let file = "thin_shell_albedo.svg";
    Figure { cols: 4, pw: 500, ph: 380, panels: panels_out }.save(&ctx.out.join(file)).expect("write svg");
    let _ = writeln!(
        md,
        "![thin-shell albedo]({file})\n\n*Figure 3a: directional albedo (channel average) vs incidence angle; top row \
         Beckmann, bottom row GGX; colours α = 0.1 (blue), 0.3 (orange), 0.6 (green), 1.0 (purple). Columns 1–2: \
         lines = reference (analytic single scattering; Heitz 2016 walk, all orders), dots = macrofacet slab. \
         Columns 3–4: the difference in units of its standard error (dashed: ±3).*\n"
    );
    let csv_path = ctx.write_csv(
        "thin_shell_albedo.csv",
        "dist,alpha,theta_deg,analytic_single_R,analytic_single_G,analytic_single_B,macro_single_R,macro_single_G,macro_single_B,se_R,se_G,se_B,macro_all_R,macro_all_G,macro_all_B,se_R,se_G,se_B,heitz_all_R,heitz_all_G,heitz_all_B,se_R,se_G,se_B,heitz_single_R,heitz_single_G,heitz_single_B,se_R,se_G,se_B",
        &csv,
    );
    let _ = writeln!(
        md,
        "{}\nWorst differences over all angles and channels, as value ± SE (z-score; angle, channel). \"Heitz single \
         |z|\" is the worst |Heitz single-bounce − analytic|/SE, a check of the references against each other. The \
         multiple-scattering share is (all − single)/all of the reference at θ = 0° / {:.0}°. Raw data: \
         [`{csv_path}`]({csv_path}).\n",
        md_table(
            &["NDF", "α", "single: macrofacet − analytic", "Heitz single |z|", "all orders: macrofacet − Heitz", "multiple-scattering share", "within expectation"],
            &rows
        ),
        angles[angles.len() - 1]
    );

    // BRDF slices.
    let slice_md = brdf_slices(ctx);
    md.push_str(&slice_md.0);
    let mut summary = vec![
        (
            "3. Thin shell, single scattering vs analytic microfacet BRDF (Beckmann, GGX; α 0.1–1; gold)".to_string(),
            format!("max |Δ albedo| {:.5}, max |z| {:.1}", summary_single.0, summary_single.1),
            yes_no(summary_single.2),
        ),
        (
            "3. Thin shell, all orders vs Heitz 2016 random walk".to_string(),
            format!("max |Δ albedo| {:.5}, max |z| {:.1}", summary_all.0, summary_all.1),
            yes_no(summary_all.2),
        ),
    ];
    summary.push(slice_md.1);
    Section { title: "3. Thin shell vs microfacet theory (seeds/000 Figs. 13–14)".into(), markdown: md, summary, seconds: 0.0 }
}

/// In-plane BRDF slices at θi = 60°: macrofacet next-event estimates (single and all orders) vs
/// the analytic single-scattering BRDF and the Heitz 2016 walk's next-event estimate.
fn brdf_slices(ctx: &Ctx) -> (String, (String, String, String)) {
    let (eta, k) = gold();
    let theta_i = 60.0f64;
    let wi = incident(theta_i);
    let thetas: Vec<f64> = (-17..=17).map(|i| 5.0 * i as f64).collect();
    // wo in the incident plane; θo > 0 on the specular side.
    let wos: Vec<DVec3> = thetas.iter().map(|t| DVec3::new(-t.to_radians().sin(), 0.0, t.to_radians().cos())).collect();
    let configs = [Dist::Beckmann(0.3), Dist::Beckmann(1.0), Dist::Ggx(0.3), Dist::Ggx(1.0)];
    let (n, chunks) = if ctx.quick { (5_000, 1) } else { (100_000, 4) };
    let jobs: Vec<(usize, bool, u64)> = (0..configs.len()).flat_map(|c| [false, true].into_iter().flat_map(move |h| (0..chunks as u64).map(move |k| (c, h, k)))).collect();
    // Per wo: sums and sums of squares of per-path all-orders and single estimates (grey).
    let results = par_map(&jobs, ctx.threads, |&(c, heitz, chunk)| {
        let dist = &configs[c];
        let m = medium(dist);
        let mut rng = Pcg32::new(SEED + 5000 + 10 * c as u64 + heitz as u64, chunk);
        let nw = wos.len();
        let mut sums = vec![[0.0f64; 4]; nw]; // Σall, Σall², Σsingle, Σsingle²
        for _ in 0..n / chunks {
            let mut all = vec![[0.0; 3]; nw];
            let mut single = vec![[0.0; 3]; nw];
            if heitz {
                heitz_nee(dist, eta, k, wi, &wos, &mut rng, &mut all, &mut single);
            } else {
                let mut event = 0;
                let mut u = || rng.next_f64();
                walk_from(&m, m.height.top(), -wi, MAX_ORDER, &mut u, |f, wi_ev, weight| {
                    for (j, wo) in wos.iter().enumerate() {
                        let p = m.phase.eval(wi_ev, *wo);
                        let t = m.transmittance(f, *wo, f64::INFINITY);
                        for ch in 0..3 {
                            let v = weight[ch] * p[ch] * t;
                            all[j][ch] += v;
                            if event == 0 {
                                single[j][ch] += v;
                            }
                        }
                    }
                    event += 1;
                });
            }
            for j in 0..nw {
                let g = (all[j][0] + all[j][1] + all[j][2]) / 3.0;
                let s = (single[j][0] + single[j][1] + single[j][2]) / 3.0;
                sums[j][0] += g;
                sums[j][1] += g * g;
                sums[j][2] += s;
                sums[j][3] += s * s;
            }
        }
        sums
    });
    let nn = (n / chunks * chunks) as f64;
    let mut md = String::new();
    let mut panels = Vec::new();
    let mut rows = Vec::new();
    let mut worst_z: f64 = 0.0;
    for (c, dist) in configs.iter().enumerate() {
        let mut tot = [vec![[0.0f64; 4]; wos.len()], vec![[0.0f64; 4]; wos.len()]];
        for (job, r) in jobs.iter().zip(&results) {
            if job.0 == c {
                let t = &mut tot[job.1 as usize];
                for j in 0..wos.len() {
                    for q in 0..4 {
                        t[j][q] += r[j][q];
                    }
                }
            }
        }
        let stat = |s: [f64; 4], q: usize| {
            let m = s[q] / nn;
            (m, ((s[q + 1] / nn - m * m).max(0.0) / (nn - 1.0)).sqrt())
        };
        let analytic: Vec<f64> = wos.iter().map(|wo| single_scattering_density(dist, eta, k, wi, *wo).iter().sum::<f64>() / 3.0).collect();
        let mut p = Panel::new(&format!("{} α = {}, θi = 60°", dist.name(), dist.alpha()), "θo (deg), + = specular side", "fr cos θo");
        p.x = Some((-85.0, 85.0));
        p.legend = LegendPos::TopLeft;
        p.legend_room = 0.45;
        let (mut mz_s, mut mz_a, mut mz_hs): (f64, f64, f64) = (0.0, 0.0, 0.0);
        let mut pts = [vec![], vec![], vec![], vec![]];
        let peak = (0..wos.len()).map(|j| stat(tot[1][j], 0).0).fold(0.0, f64::max);
        for j in 0..wos.len() {
            let (ma, mas) = stat(tot[0][j], 0);
            let (msi, mss) = stat(tot[0][j], 2);
            let (ha, has) = stat(tot[1][j], 0);
            let (hsi, hss) = stat(tot[1][j], 2);
            // Differences below 1e-9 of the slice's peak are rounding, not signal (far from the
            // lobe every estimate and the analytic value underflow together).
            let floor = 1e-9 * peak;
            mz_s = mz_s.max((msi - analytic[j]).abs() / mss.max(floor));
            mz_hs = mz_hs.max((hsi - analytic[j]).abs() / hss.max(floor));
            mz_a = mz_a.max((ma - ha).abs() / (mas * mas + has * has).sqrt().max(floor));
            pts[0].push((thetas[j], msi));
            pts[1].push((thetas[j], ma));
            pts[2].push((thetas[j], ha));
            pts[3].push((thetas[j], analytic[j]));
        }
        worst_z = worst_z.max(mz_s).max(mz_a);
        p.series.push(Series::line("analytic single", BLACK, pts[3].clone()));
        p.series.push(Series::dashed("Heitz all orders", PALETTE[1], pts[2].clone()));
        p.series.push(Series::markers("macro single", PALETTE[0], pts[0].clone(), None));
        p.series.push(Series::markers("macro all orders", PALETTE[2], pts[1].clone(), None));
        panels.push(p);
        rows.push(vec![dist.name().to_string(), format!("{}", dist.alpha()), format!("{mz_s:.1}"), format!("{mz_hs:.1}"), format!("{mz_a:.1}"), yes_no(mz_s <= Z_TOL && mz_a <= Z_TOL)]);
    }
    let file = "thin_shell_brdf_slices.svg";
    Figure { cols: 4, pw: 500, ph: 380, panels }.save(&ctx.out.join(file)).expect("write svg");
    let _ = writeln!(
        md,
        "**BRDF slices.** In the incident plane at θi = 60°, `f_r cos θo` (channel average) by next-event estimation: \
         the macrofacet walk (`slab::walk_from`, adding `weight · p(wi_event, wo) · T(f → top along wo)` at every event, \
         as `slab::reflected_density` does, for all wo at once) and the Heitz walk (adding `energy · p(−wr, wo) · \
         Φ(h)^Λ(wo)`), N = {n} paths each (seeds `Pcg32::new({} + 10·config + estimator, chunk)`).\n\n\
         ![BRDF slices]({file})\n\n*Figure 3b: black = analytic single scattering, orange dashed = Heitz 2016 all orders, \
         blue dots = macrofacet single scattering, green dots = macrofacet all orders. θo > 0 is the specular side.*\n\n{}\n\
         Worst |z| over the 35 outgoing directions.\n",
        SEED + 5000,
        md_table(&["NDF", "α", "macro single vs analytic, max |z|", "Heitz single vs analytic, max |z|", "macro all vs Heitz all, max |z|", "within expectation"], &rows)
    );
    let ok = worst_z <= Z_TOL;
    (md, ("3. Thin shell, in-plane BRDF slices at θi = 60° (single and all orders)".into(), format!("max |z| {worst_z:.1} over 4 configs × 35 directions"), yes_no(ok)))
}
