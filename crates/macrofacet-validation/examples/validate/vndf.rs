//! Comparison 2: visible normals of GP realizations vs the macrofacet vNDF (seeds/000 Fig. 10).

use crate::bruteforce::Track;
use crate::plot::{Figure, LegendPos, Panel, Series, BLUE, RED};
use crate::reference::gauss_legendre;
use crate::util::{downward, kernel_cases, md_table, par_map, yes_no, Ctx, Section};
use glam::DVec3;
use macrofacet_gpis::{visible_normals, GpisTracer, MarchSettings, Plane};
use macrofacet::ndf::MicrofacetDistribution;
use macrofacet_validation::stats::Pcg32;
use std::f64::consts::PI;
use std::fmt::Write as _;

const SEED: u64 = 2_000;
/// Display bins: cos θ_m over [−1, 1] and the azimuth relative to the incident plane.
const MU_BINS: usize = 40;
const PHI_BINS: usize = 36;
/// Cells of the 2-D (cos θ_m, φ) histogram used for the total variation.
const MU_2D: usize = 20;
const PHI_2D: usize = 18;
/// Fine quadrature cells (multiples of the display and 2-D bins).
const MU_FINE: usize = 400;
const PHI_FINE: usize = 144;


/// Azimuth of `m` relative to the incident direction's azimuth, in (−π, π]. The incident
/// direction `wi = −d` points toward −x, so φ_rel = 0 means "tilted toward the viewer".
fn phi_rel(m: DVec3) -> f64 {
    let p = m.y.atan2(m.x) - PI;
    if p <= -PI {
        p + 2.0 * PI
    } else if p > PI {
        p - 2.0 * PI
    } else {
        p
    }
}

fn mu_index(mu: f64, bins: usize) -> usize {
    (((mu.clamp(-1.0, 1.0) + 1.0) * 0.5 * bins as f64) as usize).min(bins - 1)
}

fn phi_index(phi: f64, bins: usize) -> usize {
    (((phi + PI) / (2.0 * PI) * bins as f64) as usize).min(bins - 1)
}

/// Probabilities of the fine (μ, φ_rel) cells under `pdf` (solid angle `dω = dμ dφ`), 3×3
/// Gauss–Legendre per cell, and the expected normal.
fn fine_cells(pdf: impl Fn(DVec3) -> f64) -> (Vec<f64>, DVec3) {
    let gl = gauss_legendre(3);
    let (hm, hp) = (2.0 / MU_FINE as f64, 2.0 * PI / PHI_FINE as f64);
    let mut cells = vec![0.0; MU_FINE * PHI_FINE];
    let mut mean = DVec3::ZERO;
    for i in 0..MU_FINE {
        for j in 0..PHI_FINE {
            let mut s = 0.0;
            for &(xm, wm) in &gl {
                let mu = -1.0 + hm * (i as f64 + 0.5 + 0.5 * xm);
                let st = (1.0 - mu * mu).max(0.0).sqrt();
                for &(xp, wp) in &gl {
                    let phi = -PI + hp * (j as f64 + 0.5 + 0.5 * xp);
                    let a = phi + PI; // absolute azimuth
                    let m = DVec3::new(st * a.cos(), st * a.sin(), mu);
                    let v = 0.25 * hm * hp * wm * wp * pdf(m);
                    s += v;
                    mean += v * m;
                }
            }
            cells[i * PHI_FINE + j] = s;
        }
    }
    (cells, mean)
}

struct Stats {
    tv: f64,
    floor: f64,
}

/// Total variation `½ Σ |p̂ − p|` of binned counts against bin probabilities, and its Monte
/// Carlo floor `Σ √(p(1 − p)/(2πN))` (the expected TV of an exact sampler for large N).
fn tv(counts: &[f64], probs: &[f64], n: f64) -> Stats {
    let tv = 0.5 * counts.iter().zip(probs).map(|(c, p)| (c / n - p).abs()).sum::<f64>();
    let floor = probs.iter().map(|p| (p.max(0.0) * (1.0 - p).max(0.0) / (2.0 * PI * n)).sqrt()).sum();
    Stats { tv, floor }
}

pub fn run(ctx: &Ctx) -> Section {
    let angles: Vec<f64> = vec![0.0, 45.0, 70.0, 80.0];
    let (n, chunks) = if ctx.quick { (4_000, 2) } else { (100_000, 10) };
    let cases = kernel_cases();
    // Jobs: one quadrature job per (case, angle), realization chunks, and (height field,
    // oblique incidence) brute-force track chunks.
    #[derive(Clone, Copy, PartialEq)]
    enum Kind {
        Model,
        Gpis,
        /// GPIS with a finer march (ρ = 0.99, window 128), height field only.
        Fine,
        Brute,
    }
    let mut jobs = Vec::new();
    for c in 0..cases.len() {
        for a in 0..angles.len() {
            jobs.push((c, a, Kind::Model, 0u64));
            for k in 0..chunks {
                jobs.push((c, a, Kind::Gpis, k as u64));
                if c == 0 && angles[a] > 0.0 {
                    jobs.push((c, a, Kind::Brute, k as u64));
                    jobs.push((c, a, Kind::Fine, k as u64));
                }
            }
        }
    }
    enum Out {
        Normals(Vec<DVec3>),
        Fine(Vec<DVec3>),
        Brute(Vec<DVec3>),
        Cells(Vec<f64>, DVec3),
    }
    let results = par_map(&jobs, ctx.threads, |&(c, a, kind, k)| {
        let case = &cases[c];
        let d = downward(angles[a]);
        match kind {
            Kind::Gpis | Kind::Fine => {
                let plane = Plane::default();
                let mut tracer = GpisTracer::new(&plane, case.kernel);
                let seed = if kind == Kind::Fine {
                    tracer.settings = MarchSettings { step_correlation: 0.99, window: 128, ..MarchSettings::default() };
                    SEED + 700 + a as u64
                } else {
                    SEED + 100 * c as u64 + a as u64
                };
                let mut rng = Pcg32::new(seed, k);
                let v = visible_normals(&tracer, DVec3::new(0.0, 0.0, 3.0), d, n / chunks, &mut || rng.next_f64()).expect("a stationary GPIS has no field to fail");
                if kind == Kind::Fine {
                    Out::Fine(v)
                } else {
                    Out::Normals(v)
                }
            }
            Kind::Brute => {
                let track = Track::new(angles[a], 3.0, -6.0, case.kernel.sigma, case.kernel.lengthscale.x, 0.05 * case.kernel.sigma);
                let mut rng = Pcg32::new(SEED + 500 + a as u64, k);
                Out::Brute((0..n / chunks).filter_map(|_| track.trace(3.0, &mut rng)).map(|h| h.normal).collect())
            }
            Kind::Model => {
                let (cells, mean) = fine_cells(|m| case.ndf.pdf_visible(-d, m));
                Out::Cells(cells, mean)
            }
        }
    });

    let mut md = String::new();
    let _ = writeln!(
        md,
        "Rays start at +3σ above a planar GPSS (σ = 1, α = 1 on every axis with a finite length scale) and \
         travel down at incidence θ. The **reference** normals are those of the first entering zero crossing \
         of each GP realization, `gpis::visible_normals` (the normal `∇f/|∇f|` drawn from its conditional law \
         at the crossing, seeds/004 Sec. 3.2). The **model** is `pdf_visible(wi, m) = <wi, m> D(m) / σ(wi)` \
         (seeds/000 Eq. 12) of the Beckmann NDF (height field) or the generalized NDF of seeds/000 Eq. 38 (isotropic kernel), \
         whose normals cover the whole sphere.\n\n\
         - Rays: N = {n} per (kernel, angle), in {chunks} chunks seeded `Pcg32::new({SEED} + 100·kernel + angle index, chunk)`.\n\
         - Histograms: cos θ_m in {MU_BINS} bins on [−1, 1]; azimuth φ of m relative to the incident azimuth \
         (φ = 0: the normal leans toward the viewer) in {PHI_BINS} bins; the 2-D total variation uses a \
         {MU_2D} × {PHI_2D} (cos θ_m, φ) grid. Bin probabilities of the model come from 3×3-point Gauss–Legendre \
         quadrature on a {MU_FINE} × {PHI_FINE} grid.\n\
         - Metrics: total variation TV = ½ Σ|p̂ − p| of the bin probabilities, next to its Monte Carlo floor \
         Σ √(p(1−p)/(2πN)) (what an exact sampler would score); MSE of the cos θ_m density; χ²/dof of the 2-D \
         histogram (≈ 1 when the difference is pure noise); the mean normal's difference along x (in the \
         incident plane, + = away from the viewer) and z, in units of its SE.\n\
         - **Expected agreement.** Smith's vNDF is exact for uncorrelated occluders only; the first-hit normals of \
         a GP are slightly biased toward facets that face the viewer (slope–visibility correlation). seeds/004 \
         Fig. 12 shows the Smith vNDF is excellent for squared-exponential kernels at non-grazing angles; the \
         test suite allows TV ≤ floor + 0.025 and a mean-normal error ≤ 0.03 (it measured a lean of 0.007 ± 0.002 \
         at 45°). Expect χ²/dof > 1 at this N where that small bias is resolved.\n"
    );
    let mut rows = Vec::new();
    let mut summary = Vec::new();
    let mut csv = Vec::new();
    let mut brute_rows = Vec::new();
    let mut brute_worst_z: f64 = 0.0;
    let mut fine_worst_z: f64 = 0.0;
    let mut brute_model_x: Vec<(f64, f64)> = Vec::new();
    let mut gpis_brute_x: Vec<(f64, f64)> = Vec::new();
    for (c, case) in cases.iter().enumerate() {
        let mut panels_mu = Vec::new();
        let mut panels_phi = Vec::new();
        let mut ok_case = true;
        let mut worst_excess: f64 = f64::NEG_INFINITY;
        let mut worst_mean: f64 = 0.0;
        for (a, &theta) in angles.iter().enumerate() {
            let mut normals = Vec::new();
            let mut brute = Vec::new();
            let mut fine = Vec::new();
            let mut cells = Vec::new();
            let mut mean_model = DVec3::ZERO;
            for (job, r) in jobs.iter().zip(&results) {
                if job.0 == c && job.1 == a {
                    match r {
                        Out::Normals(v) => normals.extend_from_slice(v),
                        Out::Brute(v) => brute.extend_from_slice(v),
                        Out::Fine(v) => fine.extend_from_slice(v),
                        Out::Cells(p, m) => {
                            cells = p.clone();
                            mean_model = *m;
                        }
                    }
                }
            }
            let nn = normals.len() as f64;
            let total_p: f64 = cells.iter().sum();
            // Counts on the display and 2-D grids.
            let mut c_mu = vec![0.0; MU_BINS];
            let mut c_phi = vec![0.0; PHI_BINS];
            let mut c_2d = vec![0.0; MU_2D * PHI_2D];
            let mut mean = DVec3::ZERO;
            let mut mean2 = DVec3::ZERO;
            for m in &normals {
                let p = phi_rel(*m);
                c_mu[mu_index(m.z, MU_BINS)] += 1.0;
                c_phi[phi_index(p, PHI_BINS)] += 1.0;
                c_2d[mu_index(m.z, MU_2D) * PHI_2D + phi_index(p, PHI_2D)] += 1.0;
                mean += *m;
                mean2 += *m * *m;
            }
            mean /= nn;
            let se_mean = ((mean2 / nn - mean * mean).max(DVec3::ZERO) / (nn - 1.0)).powf(0.5);
            let mut p_mu = vec![0.0; MU_BINS];
            let mut p_phi = vec![0.0; PHI_BINS];
            let mut p_2d = vec![0.0; MU_2D * PHI_2D];
            for i in 0..MU_FINE {
                for j in 0..PHI_FINE {
                    let p = cells[i * PHI_FINE + j];
                    p_mu[i * MU_BINS / MU_FINE] += p;
                    p_phi[j * PHI_BINS / PHI_FINE] += p;
                    p_2d[(i * MU_2D / MU_FINE) * PHI_2D + j * PHI_2D / PHI_FINE] += p;
                }
            }
            let s_mu = tv(&c_mu, &p_mu, nn);
            let s_phi = tv(&c_phi, &p_phi, nn);
            let s_2d = tv(&c_2d, &p_2d, nn);
            let wmu = 2.0 / MU_BINS as f64;
            let mse = c_mu.iter().zip(&p_mu).map(|(c, p)| (c / nn / wmu - p / wmu).powi(2)).sum::<f64>() / MU_BINS as f64;
            let (mut chi2, mut dof) = (0.0, 0usize);
            for (o, p) in c_2d.iter().zip(&p_2d) {
                let e = p * nn;
                if e >= 5.0 {
                    chi2 += (o - e) * (o - e) / e;
                    dof += 1;
                }
            }
            let dof = dof.saturating_sub(1).max(1);
            let dmean = mean - mean_model;
            // Brute-force track normals (height field): mean normal and 2-D TV against the model,
            // and the GPIS − brute-force mean normal.
            if !brute.is_empty() {
                let nb = brute.len() as f64;
                let mb = brute.iter().copied().sum::<DVec3>() / nb;
                let mb2 = brute.iter().map(|m| *m * *m).sum::<DVec3>() / nb;
                let sb = ((mb2 - mb * mb).max(DVec3::ZERO) / (nb - 1.0)).powf(0.5);
                let mut cb = vec![0.0; MU_2D * PHI_2D];
                for m in &brute {
                    cb[mu_index(m.z, MU_2D) * PHI_2D + phi_index(phi_rel(*m), PHI_2D)] += 1.0;
                }
                let tb = tv(&cb, &p_2d, nb);
                let dgb = mean.x - mb.x;
                let sgb = (se_mean.x * se_mean.x + sb.x * sb.x).sqrt();
                let nf = fine.len() as f64;
                let mf = fine.iter().copied().sum::<DVec3>() / nf;
                let mf2 = fine.iter().map(|m| *m * *m).sum::<DVec3>() / nf;
                let sf = ((mf2 - mf * mf).max(DVec3::ZERO) / (nf - 1.0)).powf(0.5);
                let dfb = mf.x - mb.x;
                let sfb = (sf.x * sf.x + sb.x * sb.x).sqrt();
                let dgz = mean.z - mb.z;
                let sgz = (se_mean.z * se_mean.z + sb.z * sb.z).sqrt();
                brute_worst_z = brute_worst_z.max((dgb / sgb.max(1e-300)).abs()).max((dgz / sgz.max(1e-300)).abs());
                fine_worst_z = fine_worst_z.max((dfb / sfb.max(1e-300)).abs());
                brute_model_x.push((theta, mb.x - mean_model.x));
                gpis_brute_x.push((theta, dgb));
                brute_rows.push(vec![
                    format!("{theta:.0}°"),
                    format!("{}", brute.len()),
                    format!("{:.4} / {:.4}", tb.tv, tb.floor),
                    format!("{:+.4} ({:+.1} SE)", mb.x - mean_model.x, (mb.x - mean_model.x) / sb.x.max(1e-300)),
                    format!("{:+.4} ({:+.1} SE)", mb.z - mean_model.z, (mb.z - mean_model.z) / sb.z.max(1e-300)),
                    format!("{:+.4} ({:+.1} SE)", dgb, dgb / sgb.max(1e-300)),
                    format!("{:+.4} ({:+.1} SE)", dgz, dgz / sgz.max(1e-300)),
                    format!("{:+.4} ({:+.1} SE)", dfb, dfb / sfb.max(1e-300)),
                ]);
            }
            let ok = s_2d.tv <= s_2d.floor + 0.025 && dmean.length() <= 0.03 && normals.len() == n / chunks * chunks;
            ok_case &= ok;
            worst_excess = worst_excess.max(s_2d.tv - s_2d.floor);
            worst_mean = worst_mean.max(dmean.length());
            rows.push(vec![
                case.label.to_string(),
                format!("{theta:.0}°"),
                format!("{}", normals.len()),
                format!("{:.4} / {:.4}", s_mu.tv, s_mu.floor),
                format!("{:.4} / {:.4}", s_phi.tv, s_phi.floor),
                format!("{:.4} / {:.4}", s_2d.tv, s_2d.floor),
                format!("{mse:.2e}"),
                format!("{:.2}", chi2 / dof as f64),
                format!("{:+.4} ({:+.1} SE)", dmean.x, dmean.x / se_mean.x.max(1e-300)),
                format!("{:+.4} ({:+.1} SE)", dmean.z, dmean.z / se_mean.z.max(1e-300)),
                format!("{total_p:.5}"),
                yes_no(ok),
            ]);
            for i in 0..MU_BINS {
                csv.push(format!("{},{},mu,{:.4},{:.6},{:.6}", case.file, theta, -1.0 + wmu * (i as f64 + 0.5), c_mu[i] / nn / wmu, p_mu[i] / wmu));
            }
            let wphi = 360.0 / PHI_BINS as f64;
            for j in 0..PHI_BINS {
                csv.push(format!("{},{},phi,{:.2},{:.6},{:.6}", case.file, theta, -180.0 + wphi * (j as f64 + 0.5), c_phi[j] / nn / wphi, p_phi[j] / wphi));
            }
            // Plot densities: GPIS markers with ±2 SE bars, model curve on the fine grid.
            let hist = |counts: &[f64], lo: f64, w: f64| -> (Vec<(f64, f64)>, Vec<f64>) {
                let pts = counts.iter().enumerate().map(|(i, c)| (lo + w * (i as f64 + 0.5), c / nn / w)).collect();
                let err = counts.iter().map(|c| 2.0 * ((c / nn) * (1.0 - c / nn) / nn).sqrt() / w).collect();
                (pts, err)
            };
            let (pts, err) = hist(&c_mu, -1.0, wmu);
            let wf = 2.0 / MU_FINE as f64;
            let curve: Vec<(f64, f64)> = (0..MU_FINE).map(|i| (-1.0 + wf * (i as f64 + 0.5), (0..PHI_FINE).map(|j| cells[i * PHI_FINE + j]).sum::<f64>() / wf)).collect();
            let mut p = Panel::new(&format!("θ = {theta:.0}°"), "cos θm", "density");
            p.x = Some((-1.0, 1.0));
            p.series.push(Series::line("model", RED, curve));
            p.series.push(Series::markers("GPIS", BLUE, pts, Some(err)));
            p.legend = LegendPos::TopLeft;
            panels_mu.push(p);
            let (pts, err) = hist(&c_phi, -180.0, wphi);
            let wpf = 360.0 / PHI_FINE as f64;
            let curve: Vec<(f64, f64)> = (0..PHI_FINE).map(|j| (-180.0 + wpf * (j as f64 + 0.5), (0..MU_FINE).map(|i| cells[i * PHI_FINE + j]).sum::<f64>() / wpf)).collect();
            let mut q = Panel::new(&format!("θ = {theta:.0}°"), "azimuth φ (deg)", "density");
            q.x = Some((-180.0, 180.0));
            q.series.push(Series::line("model", RED, curve));
            q.series.push(Series::markers("GPIS", BLUE, pts, Some(err)));
            q.legend = LegendPos::TopLeft;
            panels_phi.push(q);
        }
        let file = format!("vndf_{}.svg", case.file);
        let mut panels = panels_mu;
        panels.extend(panels_phi);
        Figure { cols: angles.len(), pw: 460, ph: 360, panels }.save(&ctx.out.join(&file)).expect("write svg");
        let _ = writeln!(
            md,
            "![vNDF, {label}]({file})\n\n*Figure 2{sub}: {label} kernel vs {ndf}, incidence 0°, 45°, 70°, 80° (columns). Top: density \
             of cos θ_m; bottom: density of the normal's azimuth relative to the incident plane (per degree; 0° = \
             leaning toward the viewer). Blue dots = first-crossing normals of GP realizations with ±2 SE bars, red = \
             model vNDF.*\n",
            label = case.label,
            ndf = case.ndf_label,
            sub = if c == 0 { "a" } else { "b" },
        );
        summary.push((
            format!("2. vNDF, {} vs {}", case.label, case.ndf_label),
            format!(
                "2-D TV − MC floor ≤ {worst_excess:.4}, |Δ mean normal| ≤ {worst_mean:.4} over 0°–80° (N = {n}); GP normals lean toward the viewer at grazing incidence{}",
                if c != 0 || gpis_brute_x.is_empty() {
                    String::new()
                } else if brute_worst_z > 3.0 && fine_worst_z <= 3.0 {
                    let w = gpis_brute_x.iter().fold((0.0f64, 0.0f64), |a, b| if b.1.abs() > a.1.abs() { *b } else { a });
                    format!(" (brute force agrees with GPIS at ρ = 0.99; the default ρ = 0.95 march adds up to {:+.4} in ⟨m_x⟩ at {:.0}°, see §2)", w.1, w.0)
                } else if brute_worst_z <= 3.0 {
                    " (brute force agrees with GPIS)".to_string()
                } else {
                    " (**brute force and GPIS disagree**, see §2)".to_string()
                }
            ),
            yes_no(ok_case),
        ));
    }
    let csv_path = ctx.write_csv("vndf.csv", "kernel,theta_deg,variable,bin_center,density_gpis,density_model", &csv);
    let _ = writeln!(
        md,
        "{}\nTV entries are \"measured / MC floor\". Δ⟨m_x⟩, Δ⟨m_z⟩ = GPIS − model mean normal (x lies in the incident \
         plane, pointing away from the viewer). \"∫ model\" is the quadrature's total probability (should be 1). \
         Verdict: 2-D TV ≤ floor + 0.025 and |Δ mean normal| ≤ 0.03, every ray hit. Raw data: [`{csv_path}`]({csv_path}).\n",
        md_table(
            &["kernel", "θ", "N", "TV cos θm", "TV φ", "TV 2-D", "MSE (cos θm density)", "χ²/dof (2-D)", "Δ⟨m_x⟩", "Δ⟨m_z⟩", "∫ model", "within expectation"],
            &rows
        )
    );
    let _ = writeln!(
        md,
        "**Second ground truth (height field).** First-crossing normals from the brute-force 1-D track sampler of \
         Section 1 (`bruteforce.rs`: Cholesky on a 0.05σ grid down to −6σ; along-track slope by the finite difference \
         across the crossing, cross-track slope drawn independently, which is exact for this kernel), N = {n} per angle, \
         seeds `Pcg32::new({} + angle index, chunk)`; the last column repeats the GPIS run with a finer march (ρ = 0.99, \
         window 128, seeds `Pcg32::new({} + angle index, chunk)`). It tells a property of Gaussian height fields (both \
         realization methods agree, the model does not) from an artefact of `gpis` (they disagree).\n\n{}",
        SEED + 500,
        SEED + 700,
        md_table(&["θ", "N", "brute force: TV 2-D / floor", "brute force − model ⟨m_x⟩", "brute force − model ⟨m_z⟩", "GPIS − brute force ⟨m_x⟩", "GPIS − brute force ⟨m_z⟩", "GPIS (ρ = 0.99) − brute force ⟨m_x⟩"], &brute_rows)
    );
    if !brute_rows.is_empty() {
        let list = |v: &[(f64, f64)]| v.iter().map(|(t, x)| format!("{x:+.4} at {t:.0}°")).collect::<Vec<_>>().join(", ");
        let _ = writeln!(
            md,
            "**Reading.** Brute force − model ⟨m_x⟩: {}. The realizations' first-hit normals lean further toward the \
             viewer than Smith's vNDF, increasingly so toward grazing incidence: the same correlation effect as the \
             transmittance deficit of Section 1, a property of the model (its 2-D TV still stays within floor + 0.025). \
             GPIS (ρ = 0.95) − brute force: {} (largest {brute_worst_z:.1} SE over ⟨m_x⟩, ⟨m_z⟩); with ρ = 0.99 the \
             largest is {fine_worst_z:.1} SE. {}\n",
            list(&brute_model_x),
            list(&gpis_brute_x),
            if brute_worst_z > 3.0 && fine_worst_z <= 3.0 {
                "So the default march of `gpis` (ρ = 0.95) carries a small discretisation bias in grazing first-hit normals: \
                 it misses glancing crossings (the surface grazing the ray between two samples, whose normals lean *away* \
                 from the viewer), which the finer march and the brute force (0.05σ grid) catch. It is about a quarter of \
                 the model error above; `src/gpis/mod.rs` reports the normals unchanged with ρ = 0.99 at 45°, which holds \
                 there but not at 70°–80°. Use ρ ≥ 0.99 for grazing-angle normals from `gpis`."
            } else if brute_worst_z > 3.0 {
                "**The realization references disagree beyond 3 SE even with the finer march: investigate.**"
            } else {
                "The two realization methods agree."
            }
        );
    }
    Section { title: "2. Visible-normal distributions (seeds/000 Fig. 10)".into(), markdown: md, summary, seconds: 0.0 }
}
