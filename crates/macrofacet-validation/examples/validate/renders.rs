//! Section 5: equal-spp / equal-time renders (mfrender `macrofacet` vs `gpis` media). The numbers
//! come from optional input files written by whoever runs the renders
//! (`scripts/compare_gpis.sh SCENE`); nothing is computed or invented here.
//!
//! Inputs (tab-separated, `#` starts a comment line, the first non-comment line is the header):
//! - `DIR/renders.tsv`: one row per render; required columns `scene`, `medium`, `spp`, `time_s`,
//!   `mse`; optional `image` (a path relative to DIR, embedded in the report), `notes` and
//!   `gpis_ref_noise`. `mse` is the mean squared error against the scene's reference image (state
//!   which in `notes`), `gpis_ref_noise` that reference's own noise (its MSE against its
//!   expectation), which every such MSE contains.
//! - `DIR/render_patches.tsv`: one row per image patch of a scene (the columns of
//!   [`PATCH_COLUMNS`]; `scripts/compare_gpis.sh` documents them): per patch the MSEs against the
//!   GPIS reference, its own noise, and the references' model difference with the noise removed.

use crate::util::{md_table, Ctx, Section};
use std::collections::BTreeMap;
use std::fmt::Write as _;

pub const FILE: &str = "renders.tsv";
pub const PATCH_FILE: &str = "render_patches.tsv";

/// The columns of `render_patches.tsv` this section reads.
pub const PATCH_COLUMNS: [&str; 19] = [
    "scene",
    "row",
    "col",
    "row_label",
    "col_label",
    "mean_gpis_ref",
    "noise_gpis_ref",
    "noise_macrofacet_ref",
    "mse_refs",
    "bias2",
    "bias2_se",
    "rel_diff",
    "z",
    "mse_macrofacet_spp",
    "mse_gpis_spp",
    "mse_macrofacet_time",
    "mse_macrofacet_spp_own",
    "mse_gpis_spp_own",
    "speedup_equal_mse",
];

/// A model difference counts as resolved beyond the references' noise when the patch mean
/// difference or the noise-free MSE `bias2` is this many standard errors from zero (with 16
/// patches per scene and two statistics, 3 SE keeps the chance of a false call near 1 %).
const RESOLVED_SE: f64 = 3.0;

/// A tab-separated table: header names (lower case) and data rows with their line numbers.
#[derive(Debug)]
struct Tsv {
    cols: Vec<String>,
    rows: Vec<(usize, Vec<String>)>,
}

impl Tsv {
    /// Parses `text`; `Err` names the first of `required` the header lacks, or an empty file.
    fn parse(text: &str, required: &[&str]) -> Result<Tsv, String> {
        let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l.trim_end())).filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
        let (_, header) = lines.next().ok_or_else(|| "it is empty".to_string())?;
        let cols: Vec<String> = header.split('\t').map(|s| s.trim().to_ascii_lowercase()).collect();
        if let Some(missing) = required.iter().find(|c| !cols.iter().any(|h| h == *c)) {
            return Err(format!("the header lacks the column `{missing}`"));
        }
        let rows = lines.map(|(n, l)| (n, l.split('\t').map(|s| s.trim().to_string()).collect())).collect();
        Ok(Tsv { cols, rows })
    }

    /// The field `name` of a row ("" when the row is short or the column absent).
    fn get<'a>(&self, row: &'a [String], name: &str) -> &'a str {
        self.cols.iter().position(|c| c == name).and_then(|i| row.get(i)).map_or("", |s| s.as_str())
    }
}

/// One image patch of a scene (a row of `render_patches.tsv`).
#[derive(Debug)]
struct Patch {
    row: usize,
    col: usize,
    row_label: String,
    col_label: String,
    v: BTreeMap<&'static str, f64>,
}

impl Patch {
    fn num(&self, name: &str) -> f64 {
        self.v.get(name).copied().unwrap_or(f64::NAN)
    }
    /// Whether the references differ beyond their noise (mean difference or noise-free MSE).
    fn resolved(&self) -> bool {
        self.num("z").abs() > RESOLVED_SE || self.num("bias2") > RESOLVED_SE * self.num("bias2_se")
    }
}

pub fn run(ctx: &Ctx) -> Section {
    let path = ctx.out.join(FILE);
    let mut md = String::new();
    let title = "5. Equal-spp / equal-time renders (mfrender macrofacet vs gpis)".to_string();
    let _ = writeln!(
        md,
        "This section is filled from `{FILE}` and `{PATCH_FILE}` in the output directory when they exist (written by \
         `scripts/compare_gpis.sh SCENE`; format: tab-separated, `#` comments, a header with the columns `scene`, \
         `medium`, `spp`, `time_s`, `mse` and optionally `image`, `notes`, `gpis_ref_noise`; one row per render, `mse` \
         against the scene's reference image). The numbers are measured by whoever wrote the files (see their comment \
         lines); this report only tabulates them and derives equal-spp time ratios and equal-time MSE ratios.\n"
    );
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(_) => {
            let _ = writeln!(
                md,
                "**Not available.** `{}` does not exist: run `scripts/compare_gpis.sh` (stationary sphere) and \
                 `scripts/compare_gpis.sh bench/gpis_varying.xml 256 32` (spatially varying panel). No numbers are reported \
                 until they are measured.\n",
                path.display()
            );
            return Section { title, markdown: md, summary: vec![("5. Renders (mfrender macrofacet vs gpis)".into(), "not available (no renders.tsv: run scripts/compare_gpis.sh)".into(), "—".into())], seconds: 0.0 };
        }
    };
    let tsv = match Tsv::parse(&text, &["scene", "medium", "spp", "time_s", "mse"]) {
        Ok(t) => t,
        Err(e) => {
            let _ = writeln!(md, "**`{FILE}` is malformed:** {e}.\n");
            return Section { title, markdown: md, summary: vec![("5. Renders".into(), format!("renders.tsv malformed ({e})"), "—".into())], seconds: 0.0 };
        }
    };
    struct Row {
        scene: String,
        medium: String,
        spp: String,
        time: f64,
        mse: f64,
        image: Option<String>,
        notes: String,
        ref_noise: Option<f64>,
    }
    let mut rows = Vec::new();
    let mut bad = Vec::new();
    for (ln, f) in &tsv.rows {
        match (tsv.get(f, "time_s").parse::<f64>(), tsv.get(f, "mse").parse::<f64>()) {
            (Ok(time), Ok(mse)) => rows.push(Row {
                scene: tsv.get(f, "scene").to_string(),
                medium: tsv.get(f, "medium").to_string(),
                spp: tsv.get(f, "spp").to_string(),
                time,
                mse,
                image: Some(tsv.get(f, "image").to_string()).filter(|s| !s.is_empty()),
                notes: tsv.get(f, "notes").to_string(),
                ref_noise: tsv.get(f, "gpis_ref_noise").parse().ok(),
            }),
            _ => bad.push(*ln),
        }
    }
    let noise_cell = |r: &Row| r.ref_noise.map_or("—".to_string(), |n| format!("{n:.2e}"));
    let table: Vec<Vec<String>> = rows
        .iter()
        .map(|r| vec![r.scene.clone(), r.medium.clone(), r.spp.clone(), format!("{:.2}", r.time), format!("{:.4e}", r.mse), noise_cell(r), r.notes.clone()])
        .collect();
    let _ = writeln!(md, "{}", md_table(&["scene", "medium", "spp", "time (s)", "MSE", "GPIS ref. noise", "notes"], &table));
    if !bad.is_empty() {
        let _ = writeln!(md, "Rows skipped (unparsable `time_s` or `mse`): lines {:?}.\n", bad);
    }
    // Derived comparisons between a macrofacet row and a gpis row of the same scene: at equal spp
    // the time ratio; at equal time (within 15 %) the MSE ratio. MSE·time products are not used:
    // they measure efficiency only while the MSE is pure variance (∝ 1/spp), which a bias floor
    // (model difference, reference noise) breaks; that is checked per medium below.
    let is = |r: &Row, m: &str| r.medium.eq_ignore_ascii_case(m);
    let mut derived = Vec::new();
    let mut headline = Vec::new();
    for g in rows.iter().filter(|r| is(r, "gpis")) {
        for m in rows.iter().filter(|r| is(r, "macrofacet") && r.scene == g.scene) {
            if m.spp == g.spp {
                derived.push(vec![g.scene.clone(), format!("equal spp ({})", g.spp), format!("{:.2} s vs {:.2} s", m.time, g.time), format!("{:.2e} vs {:.2e}", m.mse, g.mse), format!("macrofacet {:.2}× faster", g.time / m.time)]);
                headline.push(format!("{}: equal spp ({}): macrofacet {:.2}× faster, MSE {:.2e} vs {:.2e}", g.scene, g.spp, g.time / m.time, m.mse, g.mse));
            } else if (m.time / g.time - 1.0).abs() <= 0.15 {
                derived.push(vec![g.scene.clone(), format!("equal time ({} vs {} spp)", m.spp, g.spp), format!("{:.2} s vs {:.2} s", m.time, g.time), format!("{:.2e} vs {:.2e}", m.mse, g.mse), format!("macrofacet MSE {:.2}× lower", g.mse / m.mse)]);
                headline.push(format!("{}: equal time ({:.0} s): macrofacet MSE {:.1}× lower", g.scene, g.time, g.mse / m.mse));
            }
        }
    }
    if !derived.is_empty() {
        let _ = writeln!(md, "{}", md_table(&["scene", "comparison", "time: macrofacet vs gpis", "MSE: macrofacet vs gpis", "result"], &derived));
    }
    // Bias floor: does the MSE of a medium fall like 1/spp across its rows?
    // (spp, MSE, reference noise) of the rows, by (scene, medium).
    type MseBySpp = BTreeMap<(String, String), Vec<(f64, f64, Option<f64>)>>;
    let mut groups: MseBySpp = BTreeMap::new();
    for r in &rows {
        if let Ok(spp) = r.spp.parse::<f64>() {
            groups.entry((r.scene.clone(), r.medium.to_ascii_lowercase())).or_default().push((spp, r.mse, r.ref_noise));
        }
    }
    for ((scene, medium), v) in &groups {
        if v.len() < 2 {
            continue;
        }
        let lo = v.iter().cloned().fold((f64::INFINITY, 0.0, None), |a, b| if b.0 < a.0 { b } else { a });
        let hi = v.iter().cloned().fold((0.0, 0.0, None), |a, b| if b.0 > a.0 { b } else { a });
        let spp_ratio = hi.0 / lo.0;
        let mse_ratio = lo.1 / hi.1;
        let floored = mse_ratio < 0.5 * spp_ratio;
        // With the reference's own noise known, the floor splits into that noise and the rest.
        let parts = match hi.2 {
            Some(noise) => format!(
                "of which {noise:.1e} is the GPIS reference's own noise and {:.1e} the model difference plus this render's own \
                 variance",
                hi.1 - noise
            ),
            None => "the model difference plus the reference's own noise".to_string(),
        };
        let note = if floored {
            format!(
                "falls only {mse_ratio:.1}× for {spp_ratio:.0}× the samples: it is dominated by a floor of ≈ {:.1e} ({parts}), \
                 so it measures agreement, not convergence speed",
                hi.1
            )
        } else {
            format!("falls {mse_ratio:.1}× for {spp_ratio:.0}× the samples (variance-dominated)")
        };
        let _ = writeln!(md, "- `{scene}`, {medium}: the MSE {note}.\n");
        if floored {
            let noise = hi.2.map_or(String::new(), |n| format!(" (GPIS reference noise {n:.1e})"));
            headline.push(format!("{scene} {medium} MSE vs the GPIS reference has a floor ≈ {:.1e}{noise}", hi.1));
        }
    }
    patches_markdown(ctx, &mut md, &mut headline);
    for r in &rows {
        if let Some(img) = &r.image {
            if ctx.out.join(img).exists() {
                let _ = writeln!(md, "![{} — {} ({} spp)]({img})\n\n*{} — {} medium, {} spp, {:.2} s, MSE {:.4e}.*\n", r.scene, r.medium, r.spp, r.scene, r.medium, r.spp, r.time, r.mse);
            } else {
                let _ = writeln!(md, "(image `{img}` listed for {} / {} not found next to the report)\n", r.scene, r.medium);
            }
        }
    }
    let headline = if headline.is_empty() { format!("{} render rows (no macrofacet/gpis pair)", rows.len()) } else { headline.join("; ") };
    Section { title, markdown: md, summary: vec![("5. Renders, mfrender macrofacet vs gpis (measured input)".into(), headline, "—".into())], seconds: 0.0 }
}

/// Each scene's patches, scenes in file order.
type PatchesByScene = Vec<(String, Vec<Patch>)>;

/// Reads `render_patches.tsv` (if any) into patches by scene, in file order.
fn read_patches(text: &str) -> Result<(PatchesByScene, Vec<usize>), String> {
    let tsv = Tsv::parse(text, &PATCH_COLUMNS)?;
    let mut scenes: Vec<(String, Vec<Patch>)> = Vec::new();
    let mut bad = Vec::new();
    for (ln, f) in &tsv.rows {
        let (Ok(row), Ok(col)) = (tsv.get(f, "row").parse::<usize>(), tsv.get(f, "col").parse::<usize>()) else {
            bad.push(*ln);
            continue;
        };
        // Numbers; "nan" (e.g. an equal-MSE ratio without a measurable variance) is kept as NaN.
        let v: Option<BTreeMap<&'static str, f64>> = PATCH_COLUMNS[5..].iter().map(|&c| tsv.get(f, c).parse::<f64>().ok().map(|x| (c, x))).collect();
        let Some(v) = v else {
            bad.push(*ln);
            continue;
        };
        let patch = Patch { row, col, row_label: tsv.get(f, "row_label").to_string(), col_label: tsv.get(f, "col_label").to_string(), v };
        let scene = tsv.get(f, "scene").to_string();
        match scenes.iter_mut().find(|(s, _)| *s == scene) {
            Some((_, list)) => list.push(patch),
            None => scenes.push((scene, vec![patch])),
        }
    }
    Ok((scenes, bad))
}

/// The per-patch tables of every scene in `render_patches.tsv`.
fn patches_markdown(ctx: &Ctx, md: &mut String, headline: &mut Vec<String>) {
    let Ok(text) = std::fs::read_to_string(ctx.out.join(PATCH_FILE)) else {
        let _ = writeln!(md, "No per-patch comparison (`{PATCH_FILE}` does not exist: written by `scripts/compare_gpis.sh`).\n");
        return;
    };
    let (scenes, bad) = match read_patches(&text) {
        Ok(p) => p,
        Err(e) => {
            let _ = writeln!(md, "**`{PATCH_FILE}` is malformed:** {e}.\n");
            headline.push(format!("render_patches.tsv malformed ({e})"));
            return;
        }
    };
    if !bad.is_empty() {
        let _ = writeln!(md, "Patch rows skipped (unparsable numbers): lines {:?}.\n", bad);
    }
    let _ = writeln!(
        md,
        "### Per patch\n\nEach image is cut into patches (row 0 at the top). Against the GPIS reference: the MSE of the \
         equal-spp macrofacet and gpis renders and of the equal-time macrofacet render, beside the **GPIS reference's \
         own noise** (its MSE against its expectation, from two independent halves), which every such MSE contains. \
         References: their relative mean difference Δ (macrofacet − gpis) with its z-score, and the model difference \
         `bias²` = their MSE with both references' noise removed (an unbiased estimate of the mean squared difference \
         of the expectations; ± one SE). A patch is marked **beyond noise** when |z| > {RESOLVED_SE} or `bias²` > \
         {RESOLVED_SE} SE. Speed-up at equal MSE = (gpis time × gpis variance) / (macrofacet time × macrofacet \
         variance) at equal spp, the variances being each render's MSE against its own method's reference minus that \
         reference's noise (so the model difference does not enter; times are whole-image times).\n"
    );
    for (scene, patches) in &scenes {
        let table: Vec<Vec<String>> = patches
            .iter()
            .map(|p| {
                let labels = [p.row_label.as_str(), p.col_label.as_str()].iter().filter(|l| !l.is_empty() && **l != "-").copied().collect::<Vec<_>>().join(", ");
                vec![
                    format!("{},{}", p.row, p.col),
                    if labels.is_empty() { "—".into() } else { labels },
                    format!("{:.3}", p.num("mean_gpis_ref")),
                    format!("{:.2e}", p.num("noise_gpis_ref")),
                    format!("{:.2e}", p.num("mse_macrofacet_spp")),
                    format!("{:.2e}", p.num("mse_gpis_spp")),
                    format!("{:.2e}", p.num("mse_macrofacet_time")),
                    format!("{:+.2} % (z {:+.1})", 100.0 * p.num("rel_diff"), p.num("z")),
                    format!("{:.1e} ± {:.1e}", p.num("bias2"), p.num("bias2_se")),
                    if p.resolved() { "**beyond noise**".into() } else { "within noise".into() },
                    format!("{:.1}×", p.num("speedup_equal_mse")),
                ]
            })
            .collect();
        let _ = writeln!(md, "**`{scene}`**\n");
        let _ = writeln!(
            md,
            "{}",
            md_table(
                &["patch", "parameters", "GPIS ref. mean", "GPIS ref. noise", "MSE macrofacet (equal spp)", "MSE gpis (equal spp)", "MSE macrofacet (equal time)", "refs: Δ mean", "refs: bias² ± SE", "model difference", "speed-up at equal MSE"],
                &table
            )
        );
        let resolved: Vec<&Patch> = patches.iter().filter(|p| p.resolved()).collect();
        let worst = patches.iter().max_by(|a, b| a.num("rel_diff").abs().total_cmp(&b.num("rel_diff").abs()));
        let speedups: Vec<f64> = patches.iter().map(|p| p.num("speedup_equal_mse")).filter(|s| s.is_finite()).collect();
        let (lo, hi) = speedups.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &s| (lo.min(s), hi.max(s)));
        let mut line = format!("{scene}: {} of {} patches differ beyond the references' noise", resolved.len(), patches.len());
        if let Some(w) = worst {
            line += &format!(" (largest |Δ| {:.2} % at patch {},{}, z {:+.1})", 100.0 * w.num("rel_diff").abs(), w.row, w.col, w.num("z"));
        }
        if !speedups.is_empty() {
            line += &format!("; speed-up at equal MSE {lo:.1}–{hi:.1}×");
        }
        let _ = writeln!(md, "- {line}.\n");
        headline.push(line);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patches_parse_by_scene_and_flag_differences_beyond_noise() {
        let header = PATCH_COLUMNS.join("\t");
        let line = |scene: &str, row: usize, z: f64, bias2: f64| {
            format!("{scene}\t{row}\t0\tl=0.2\tsigma=0.004\t0.5\t1e-4\t2e-5\t3e-4\t{bias2}\t1e-5\t0.01\t{z}\t1e-3\t4e-3\t5e-4\t9e-4\t4e-3\tnan")
        };
        let text = format!("# comment\n{header}\n{}\n{}\n{}\nbad\trow\n", line("a.xml", 0, 0.5, 1e-5), line("a.xml", 1, -4.0, 0.0), line("b.xml", 0, 0.0, 5e-5));
        let (scenes, bad) = read_patches(&text).expect("parses");
        assert_eq!(bad, vec![6]);
        assert_eq!(scenes.iter().map(|(s, p)| (s.as_str(), p.len())).collect::<Vec<_>>(), vec![("a.xml", 2), ("b.xml", 1)]);
        let flags: Vec<bool> = scenes.iter().flat_map(|(_, p)| p.iter().map(Patch::resolved)).collect();
        assert_eq!(flags, vec![false, true, true]); // |z| = 4; bias2 = 5 SE
        assert!(scenes[0].1[0].num("speedup_equal_mse").is_nan());
        assert_eq!(scenes[0].1[1].row_label, "l=0.2");
        assert!(read_patches("scene\trow\n").unwrap_err().contains("`col`"));
    }

    #[test]
    fn renders_tsv_header_checks() {
        let t = Tsv::parse("# c\nscene\tmedium\tspp\ttime_s\tmse\tgpis_ref_noise\nx\tgpis\t64\t1.5\t2e-3\t1e-4\n", &["scene", "mse"]).unwrap();
        assert_eq!(t.get(&t.rows[0].1, "gpis_ref_noise"), "1e-4");
        assert_eq!(t.get(&t.rows[0].1, "image"), "");
        assert_eq!(t.rows[0].0, 3);
        assert!(Tsv::parse("", &[]).is_err());
        assert!(Tsv::parse("scene\n", &["mse"]).unwrap_err().contains("`mse`"));
    }
}
