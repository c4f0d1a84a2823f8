//! Comparison 1: transmittance of a planar GPSS along rays (seeds/000 Fig. 7).

use crate::bruteforce::Track;
use crate::reference::{normal_cdf, Dist};
use crate::plot::{Band, Figure, LegendPos, Panel, Series, BLUE, GRAY, GREEN, ORANGE, RED};
use crate::util::{downward, kernel_cases, md_table, par_map, yes_no, Ctx, Section};
use glam::DVec3;
use macrofacet_gpis::{transmittance_curve, GpisTracer, MarchSettings, Plane};
use macrofacet::height::HeightProfile;
use macrofacet::ndf::Ndf;
use macrofacet_validation::stats::Pcg32;
use macrofacet::{MacrofacetMedium, MacrofacetPhase, MicroBsdf, VndfSampling};
use std::f64::consts::SQRT_2;
use std::fmt::Write as _;

const SEED: u64 = 1_000;
const F0: f64 = 3.0;


fn medium(ndf: Ndf) -> MacrofacetMedium {
    MacrofacetMedium {
        height: HeightProfile::new(1.0, F0).unwrap(),
        phase: MacrofacetPhase { ndf, micro_bsdf: MicroBsdf::Mirror { specular_reflectance: [1.0; 3] }, sampling: VndfSampling::Exact },
    }
}

/// Which estimate a job computes.
#[derive(Clone, Copy, PartialEq)]
enum Est {
    /// `gpis::transmittance_curve`, default march.
    Gpis,
    /// The same with a finer march (ρ = 0.99, window 128).
    Fine,
    /// Height field only: brute-force 1-D track realizations (`bruteforce.rs`).
    Brute,
}

struct Job {
    case: usize,
    angle: usize,
    est: Est,
    chunk: u64,
    n: usize,
}

/// Grid spacing of the brute-force track, in units of σ.
const BRUTE_DS: f64 = 0.05;

/// Survival counts per depth and exhausted marches of one chunk.
struct Counts {
    survived: Vec<f64>,
    n: f64,
    exhausted: usize,
}

pub fn run(ctx: &Ctx) -> Section {
    let angles = [0.0, 45.0, 70.0];
    let (n, chunks) = if ctx.quick { (4_000, 2) } else { (200_000, 20) };
    let n_fine = n / 4;
    let heights: Vec<f64> = (0..=120).map(|i| F0 - 0.05 * i as f64).collect();
    let cases = kernel_cases();
    let mut jobs = Vec::new();
    for c in 0..cases.len() {
        for a in 0..angles.len() {
            for est in [Est::Gpis, Est::Fine, Est::Brute] {
                if est == Est::Brute && (c != 0 || angles[a] == 0.0) {
                    continue; // height field only; a vertical ray needs no realization
                }
                let total = if est == Est::Fine { n_fine } else { n };
                for k in 0..chunks {
                    jobs.push(Job { case: c, angle: a, est, chunk: k as u64, n: total / chunks });
                }
            }
        }
    }
    let results = par_map(&jobs, ctx.threads, |job| {
        let case = &cases[job.case];
        let d = downward(angles[job.angle]);
        let est_index = match job.est {
            Est::Gpis => 0,
            Est::Fine => 1,
            Est::Brute => 2,
        };
        let seed = SEED + 100 * job.case as u64 + 10 * job.angle as u64 + est_index;
        let mut rng = Pcg32::new(seed, job.chunk);
        if job.est == Est::Brute {
            let l = case.kernel.lengthscale.x;
            let track = Track::new(angles[job.angle], F0, -F0 - 0.5, case.kernel.sigma, l, BRUTE_DS * case.kernel.sigma);
            let mut survived = vec![0.0; heights.len()];
            for _ in 0..job.n {
                let zc = track.trace(F0, &mut rng).map_or(f64::NEG_INFINITY, |h| h.z);
                for (s, &h) in survived.iter_mut().zip(&heights) {
                    if zc < h {
                        *s += 1.0;
                    }
                }
            }
            return Counts { survived, n: job.n as f64, exhausted: 0 };
        }
        let plane = Plane::default();
        let mut tracer = GpisTracer::new(&plane, case.kernel);
        if job.est == Est::Fine {
            tracer.settings = MarchSettings { step_correlation: 0.99, window: 128, ..MarchSettings::default() };
        }
        let distances: Vec<f64> = heights.iter().map(|h| (F0 - h) / -d.z).collect();
        let est = transmittance_curve(&tracer, DVec3::new(0.0, 0.0, F0), d, &distances, job.n, &mut || rng.next_f64()).expect("a stationary GPIS has no field to fail");
        Counts { survived: est.transmittance.iter().map(|t| t * job.n as f64).collect(), n: job.n as f64, exhausted: est.exhausted }
    });
    // Merge the chunks.
    let mut merged: Vec<Vec<Counts>> = (0..cases.len()).map(|_| Vec::new()).collect();
    for c in 0..cases.len() {
        for a in 0..angles.len() {
            for est in [Est::Gpis, Est::Fine, Est::Brute] {
                let mut acc = Counts { survived: vec![0.0; heights.len()], n: 0.0, exhausted: 0 };
                for (job, r) in jobs.iter().zip(&results) {
                    if job.case == c && job.angle == a && job.est == est {
                        for (s, x) in acc.survived.iter_mut().zip(&r.survived) {
                            *s += x;
                        }
                        acc.n += r.n;
                        acc.exhausted += r.exhausted;
                    }
                }
                merged[c].push(acc);
            }
        }
    }

    let mut md = String::new();
    let mut summary = Vec::new();
    let _ = writeln!(
        md,
        "A ray starts at `f0 = +3σ` (the shell's top face; σ = 1, α = 1, i.e. l = √2σ, the setting of \
         seeds/000 Fig. 7) and travels down into a planar GPSS at incidence θ from the normal. The \
         **reference** is the fraction of GP realizations whose zero level set the ray has not yet \
         crossed, `gpis::transmittance_curve` (ray marching in function space, seeds/004; start \
         conditioned on `f(o) > 0`, step correlation ρ = 0.95, window 64). The **model** is the closed \
         form `MacrofacetMedium::transmittance(3σ, d, t) = (Φ(f(t)/σ)/Φ(3))^(−Λ(d))`. T is sampled at \
         121 depths `f = 3σ … −3σ` along each ray.\n"
    );
    let _ = writeln!(
        md,
        "- Realizations: N = {n} per (kernel, angle), in {chunks} chunks seeded `Pcg32::new({SEED} + 100·kernel + 10·angle index, chunk)`; \
         a convergence check with a finer march (ρ = 0.99, window 128) uses N = {n_fine} (seed + 1).\n\
         - **Expected agreement.** Height field ↔ Beckmann: the macrofacet extinction is Smith's, which \
         ignores the correlation between the heights the ray passes over; for Gaussian height fields \
         this is known to be accurate to about 0.01 in T (design notes: ~0.01 in a numpy study; \
         `tests/gpis.rs` allows 3 SE + 0.015). At θ = 0° both are exact (a vertical ray in a height \
         field sees one height: `T = Φ(f)/Φ(3)`), so that row checks the machinery. Isotropic kernel ↔ \
         generalized macrofacet: agreement in the upper shell, then a drift in the lower shell because \
         the macrofacet assumes the crossings are uncorrelated (paper Fig. 7: \"a slight difference in \
         the latter half\"); tolerance 3 SE + 0.015 for f ≥ 1σ as in the test suite, and |ΔT| ≤ 0.06 everywhere.\n"
    );
    let mut rows = Vec::new();
    let mut csv = Vec::new();
    let mut brute_rows = Vec::new();
    let mut brute_worst_z: f64 = 0.0;
    let mut smith_worst: f64 = 0.0;
    let mut brute_by_angle: Vec<(f64, f64)> = Vec::new();
    let mut fine_worst_z: f64 = 0.0;
    let mut failed: Vec<String> = Vec::new();
    for (c, case) in cases.iter().enumerate() {
        let m = medium(case.ndf);
        let mut panels_t = Vec::new();
        let mut panels_d = Vec::new();
        let mut ok_case = true;
        let mut worst_upper: f64 = 0.0;
        let mut worst_lower: f64 = 0.0;
        for (a, &theta) in angles.iter().enumerate() {
            let d = downward(theta);
            let coarse = &merged[c][3 * a];
            let fine = &merged[c][3 * a + 1];
            let brute = &merged[c][3 * a + 2];
            let t_brute: Option<Vec<f64>> = (brute.n > 0.0).then(|| brute.survived.iter().map(|s| s / brute.n).collect());
            let t_gp: Vec<f64> = coarse.survived.iter().map(|s| s / coarse.n).collect();
            let se: Vec<f64> = t_gp.iter().map(|t| (t * (1.0 - t) / coarse.n).sqrt()).collect();
            let t_fine: Vec<f64> = fine.survived.iter().map(|s| s / fine.n).collect();
            let se_fine: Vec<f64> = t_fine.iter().map(|t| (t * (1.0 - t) / fine.n).sqrt()).collect();
            let t_mf: Vec<f64> = heights.iter().map(|h| m.transmittance(F0, d, (F0 - h) / -d.z)).collect();
            for i in 0..heights.len() {
                let tb = t_brute.as_ref().map_or(String::new(), |v| format!("{:.6}", v[i]));
                csv.push(format!("{},{},{:.2},{:.6},{:.6},{:.6},{:.6},{:.6},{}", case.file, theta, heights[i], t_gp[i], se[i], t_fine[i], se_fine[i], t_mf[i], tb));
            }
            // Brute force (height field): its worst difference to the macrofacet, and to the GPIS;
            // and the closed form against Smith's formula written independently.
            if let Some(tb) = &t_brute {
                let sb: Vec<f64> = tb.iter().map(|t| (t * (1.0 - t) / brute.n).sqrt()).collect();
                let mut wu = (0.0f64, 0.0, 0.0);
                let mut wl = (0.0f64, 0.0, 0.0);
                let mut wz: f64 = 0.0;
                let mut wg: f64 = 0.0;
                let mut smith: f64 = 0.0;
                let lambda = Dist::Beckmann(1.0).lambda(-d); // Λ of the upward direction −d
                for i in 0..heights.len() {
                    let dd = tb[i] - t_mf[i];
                    let w = if heights[i] >= -1e-9 { &mut wu } else { &mut wl };
                    if dd.abs() > w.0.abs() {
                        *w = (dd, heights[i], sb[i]);
                    }
                    let dg = t_gp[i] - tb[i];
                    wg = wg.max(dg.abs());
                    let s2 = (se[i] * se[i] + sb[i] * sb[i]).sqrt();
                    if s2 > 0.0 {
                        wz = wz.max(dg.abs() / s2);
                    }
                    let t_smith = (normal_cdf(heights[i]) / normal_cdf(F0)).powf(1.0 + lambda);
                    smith = smith.max((t_mf[i] - t_smith).abs());
                }
                brute_worst_z = brute_worst_z.max(wz);
                brute_by_angle.push((theta, if wu.0.abs() > wl.0.abs() { wu.0 } else { wl.0 }));
                smith_worst = smith_worst.max(smith);
                brute_rows.push(vec![
                    format!("{theta:.0}°"),
                    format!("{}", brute.n),
                    format!("{:+.4} ± {:.4} (f = {:+.2}σ)", wu.0, wu.2, wu.1),
                    format!("{:+.4} ± {:.4} (f = {:+.2}σ)", wl.0, wl.2, wl.1),
                    format!("{wg:.4} ({wz:.1} SE)"),
                    format!("{smith:.1e}"),
                ]);
            }
            // Worst differences in the upper (f ≥ 0) and lower (f < 0) shell.
            let worst = |upper: bool| {
                let mut best = (0.0f64, 0.0, 0.0);
                for i in 0..heights.len() {
                    if (heights[i] >= -1e-9) == upper {
                        let diff = t_gp[i] - t_mf[i];
                        if diff.abs() > best.0.abs() {
                            best = (diff, heights[i], se[i]);
                        }
                    }
                }
                best
            };
            let (du, hu, su) = worst(true);
            let (dl, hl, sl) = worst(false);
            worst_upper = worst_upper.max(du.abs());
            worst_lower = worst_lower.max(dl.abs());
            let max_z = (0..heights.len()).map(|i| if se[i] > 0.0 { (t_gp[i] - t_mf[i]).abs() / se[i] } else { 0.0 }).fold(0.0, f64::max);
            let (fine_diff, fine_z) = (0..heights.len())
                .map(|i| {
                    let dd = t_fine[i] - t_gp[i];
                    let s = (se[i] * se[i] + se_fine[i] * se_fine[i]).sqrt();
                    (dd.abs(), if s > 0.0 { dd.abs() / s } else { 0.0 })
                })
                .fold((0.0f64, 0.0f64), |acc, x| (acc.0.max(x.0), acc.1.max(x.1)));
            fine_worst_z = fine_worst_z.max(fine_z);
            // Verdict against the stated expectation.
            let ok = (0..heights.len()).all(|i| {
                let diff = (t_gp[i] - t_mf[i]).abs();
                if c == 0 || heights[i] >= 1.0 {
                    diff <= 3.0 * se[i] + 0.015
                } else {
                    diff <= 0.06
                }
            });
            ok_case &= ok;
            if !ok {
                failed.push(format!("{} at {theta:.0}° (worst ΔT {:+.4} at f = {:+.2}σ)", case.label, if du.abs() > dl.abs() { du } else { dl }, if du.abs() > dl.abs() { hu } else { hl }));
            }
            rows.push(vec![
                case.label.to_string(),
                format!("{theta:.0}°"),
                format!("{n}"),
                format!("{du:+.4} ± {su:.4} (f = {hu:+.2}σ)"),
                format!("{dl:+.4} ± {sl:.4} (f = {hl:+.2}σ)"),
                format!("{max_z:.1}"),
                format!("{fine_diff:.4} ({fine_z:.1} SE)"),
                format!("{}", coarse.exhausted + fine.exhausted),
                yes_no(ok),
            ]);
            // Plots: T with the ±2 SE band, and the difference.
            let pts = |v: &[f64]| heights.iter().zip(v).map(|(&h, &t)| (h, t)).collect::<Vec<_>>();
            let mut p = Panel::new(&format!("θ = {theta:.0}°"), "f/σ (ray depth)", "T");
            p.x = Some((F0, -F0));
            p.y = Some((0.0, 1.02));
            p.bands.push(Band {
                label: "GPIS ±2 SE".into(),
                color: BLUE,
                alpha: 0.25,
                x: heights.clone(),
                lo: t_gp.iter().zip(&se).map(|(t, s)| t - 2.0 * s).collect(),
                hi: t_gp.iter().zip(&se).map(|(t, s)| t + 2.0 * s).collect(),
            });
            p.series.push(Series::line("GPIS", BLUE, pts(&t_gp)));
            p.series.push(Series::dashed("macrofacet", RED, pts(&t_mf)));
            p.legend = LegendPos::BottomLeft;
            panels_t.push(p);
            let mut q = Panel::new(&format!("θ = {theta:.0}°: GPIS − macrofacet"), "f/σ (ray depth)", "ΔT");
            q.x = Some((F0, -F0));
            q.bands.push(Band {
                label: "±2 SE".into(),
                color: GRAY,
                alpha: 0.3,
                x: heights.clone(),
                lo: se.iter().map(|s| -2.0 * s).collect(),
                hi: se.iter().map(|s| 2.0 * s).collect(),
            });
            q.hlines.push((0.0, GRAY, false));
            q.series.push(Series::line("ρ = 0.95", BLUE, heights.iter().enumerate().map(|(i, &h)| (h, t_gp[i] - t_mf[i])).collect()));
            let mut fine_series = Series::line("ρ = 0.99", GREEN, heights.iter().enumerate().map(|(i, &h)| (h, t_fine[i] - t_mf[i])).collect());
            fine_series.style = crate::plot::Style::Line { width: 1.2, dash: None };
            q.series.push(fine_series);
            if let Some(tb) = &t_brute {
                let mut bs = Series::line("1-D brute force", ORANGE, heights.iter().enumerate().map(|(i, &h)| (h, tb[i] - t_mf[i])).collect());
                bs.style = crate::plot::Style::Line { width: 1.6, dash: Some((5.0, 3.0)) };
                q.series.push(bs);
            }
            q.legend = LegendPos::BottomLeft;
            panels_d.push(q);
        }
        let file = format!("transmittance_{}.svg", case.file);
        let mut panels = panels_t;
        panels.extend(panels_d);
        Figure { cols: 3, pw: 560, ph: 400, panels }.save(&ctx.out.join(&file)).expect("write svg");
        let _ = writeln!(
            md,
            "![transmittance, {label}]({file})\n\n*Figure 1{sub}: {label} kernel vs {ndf}. Top: transmittance along the ray vs the \
             ray's signed distance f/σ to the mean plane (the ray enters at +3σ on the left); blue = realizations \
             (GPIS) with its ±2 SE band, red dashed = macrofacet closed form. Bottom: GPIS − macrofacet for the \
             default march (blue, ρ = 0.95) and the fine march (green, ρ = 0.99), grey band = ±2 SE of the \
             default run.*\n",
            label = case.label,
            ndf = case.ndf_label,
            sub = if c == 0 { "a" } else { "b" },
        );
        summary.push((
            format!("1. Transmittance, {} vs {}", case.label, case.ndf_label),
            format!(
                "max |ΔT| upper shell {worst_upper:.4}, lower shell {worst_lower:.4} (0°/45°/70°, N = {n}){}",
                if !ok_case && c == 0 && brute_worst_z <= 4.5 && smith_worst < 1e-9 {
                    "; the excess (70°) is Smith's model error: an independent brute-force realization agrees with GPIS and the closed form equals Smith's formula (§1)"
                } else {
                    ""
                }
            ),
            yes_no(ok_case),
        ));
    }
    let csv_path = ctx.write_csv("transmittance.csv", "kernel,theta_deg,f_over_sigma,T_gpis,se_gpis,T_gpis_fine,se_gpis_fine,T_macrofacet,T_bruteforce", &csv);
    let _ = writeln!(
        md,
        "{}\nΔT = T_GPIS − T_macrofacet; \"max |ΔT|/SE\" is over all 121 depths; the fine-march column is the largest \
         |T(ρ = 0.99) − T(ρ = 0.95)| over the curve, with its size in combined standard errors — a discretisation \
         error of the reference would show up there. \"exhausted\" counts marches that hit the sample cap \
         (counted as not crossed). Raw data: [`{csv_path}`]({csv_path}).\n",
        md_table(
            &["kernel", "θ", "N", "worst ΔT, upper shell (f ≥ 0)", "worst ΔT, lower shell (f < 0)", "max |ΔT|/SE", "fine march |ΔT|", "exhausted", "within expectation"],
            &rows
        )
    );
    let probe = Track::new(angles[angles.len() - 1], F0, -F0 - 0.5, 1.0, SQRT_2, BRUTE_DS);
    let _ = writeln!(
        md,
        "**Second ground truth (height field).** `examples/validate/bruteforce.rs` samples the 1-D GP of the heights \
         along the ray's horizontal track directly (Cholesky factor of the kernel matrix on a {BRUTE_DS}σ grid — {} points at {:.0}°, relative \
         nugget {:.0e} — drawn row by row until the ray first dips below the surface; start conditioned on \
         h(0) < 3σ by rejection), sharing no code with `gpis`. N = {n} per angle, seeds `Pcg32::new({SEED} + 10·angle index + 2, \
         chunk)`. The last column compares the library's closed form with Smith's `(Φ(f)/Φ(3))^(1+Λ(−d))` evaluated \
         with the independent Beckmann Λ of `reference.rs`.\n\n{}",
        probe.points(),
        angles[angles.len() - 1],
        probe.jitter,
        md_table(&["θ", "N", "brute force − macrofacet, upper shell", "brute force − macrofacet, lower shell", "GPIS − brute force, max |Δ|", "closed form − Smith formula, max |Δ|"], &brute_rows)
    );
    if !failed.is_empty() {
        let _ = writeln!(
            md,
            "**Investigation of the disagreement.** Beyond the stated expectation: {}. {} {} {}\n",
            failed.join("; "),
            if brute_worst_z <= 4.5 {
                format!("The two realization-based references agree with each other (largest |GPIS − brute force| is {brute_worst_z:.1} combined SE over all depths and angles);")
            } else {
                format!("**The two realization-based references disagree** (|GPIS − brute force| up to {brute_worst_z:.1} combined SE): one of them is wrong, which must be resolved before the model is judged;")
            },
            if fine_worst_z <= 4.5 {
                format!("the default and fine marches agree (≤ {fine_worst_z:.1} SE);")
            } else {
                format!("the default and fine marches differ by up to {fine_worst_z:.1} SE (discretisation of the march matters);")
            },
            if smith_worst < 1e-9 && brute_worst_z <= 4.5 {
                format!(
                    "and the library's transmittance equals Smith's closed form to {smith_worst:.0e}. So the library implements \
                     the model correctly; what the realizations measure is the error of the model itself, Smith's \
                     uncorrelated-occluder assumption behind the macrofacet extinction (seeds/000 Eq. 14): worst brute force − \
                     macrofacet difference {}. It grows toward grazing incidence (per σ of descent the ray crosses tan θ · σ of \
                     surface: 0.7 correlation lengths at 45°, 1.9 at 70°), while the paper's Fig. 7 and the test suite's \
                     0.015 tolerance were set at 45°. A \
                     negative difference means the realizations intercept the ray *earlier* than Smith predicts. This is a \
                     limitation of the model at grazing angles, not a bug in the library.",
                    brute_by_angle.iter().map(|(t, w)| format!("{w:+.4} at {t:.0}°")).collect::<Vec<_>>().join(", ")
                )
            } else {
                format!("the library's transmittance differs from Smith's closed form by up to {smith_worst:.1e}.")
            }
        );
    }
    Section { title: "1. Transmittance of a planar GPSS (seeds/000 Fig. 7)".into(), markdown: md, summary, seconds: 0.0 }
}
