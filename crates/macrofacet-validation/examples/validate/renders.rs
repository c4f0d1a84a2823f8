//! Section 5: equal-spp / equal-time renders (mfrender `macrofacet` vs `gpis` media). The numbers
//! come from an optional input file written by whoever runs the renders; nothing is computed or
//! invented here.
//!
//! Input: `DIR/renders.tsv`, tab-separated, `#` starts a comment line, first non-comment line is
//! the header and must contain the columns `scene`, `medium`, `spp`, `time_s`, `mse`; optional
//! columns `image` (a path relative to DIR, embedded in the report) and `notes`. `mse` is the mean
//! squared error against the scene's reference image (state which in `notes`).

use crate::util::{md_table, Ctx, Section};
use std::collections::BTreeMap;
use std::fmt::Write as _;

pub const FILE: &str = "renders.tsv";

pub fn run(ctx: &Ctx) -> Section {
    let path = ctx.out.join(FILE);
    let mut md = String::new();
    let title = "5. Equal-spp / equal-time renders (mfrender macrofacet vs gpis)".to_string();
    let _ = writeln!(
        md,
        "This section is filled from `{FILE}` in the output directory when it exists (format: tab-separated, `#` \
         comments, a header with the columns `scene`, `medium`, `spp`, `time_s`, `mse` and optionally `image`, \
         `notes`; one row per render, `mse` against the scene's reference image). The numbers are measured by whoever \
         wrote the file (see its comment line); this report only tabulates them and derives equal-spp time ratios and \
         equal-time MSE ratios.\n"
    );
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(_) => {
            let _ = writeln!(
                md,
                "**Not available.** `{}` does not exist: the equal-spp / equal-time renders need the mfrender `gpis` \
                 medium, which is not yet available. No numbers are reported until they are measured.\n",
                path.display()
            );
            return Section { title, markdown: md, summary: vec![("5. Renders (mfrender macrofacet vs gpis)".into(), "not available (no renders.tsv; mfrender `gpis` medium pending)".into(), "—".into())], seconds: 0.0 };
        }
    };
    let mut lines = text.lines().map(str::trim_end).filter(|l| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let Some(header) = lines.next() else {
        let _ = writeln!(md, "**`{FILE}` is empty.**\n");
        return Section { title, markdown: md, summary: vec![("5. Renders".into(), "renders.tsv empty".into(), "—".into())], seconds: 0.0 };
    };
    let cols: Vec<String> = header.split('\t').map(|s| s.trim().to_ascii_lowercase()).collect();
    let col = |name: &str| cols.iter().position(|c| c == name);
    let required = ["scene", "medium", "spp", "time_s", "mse"];
    if let Some(missing) = required.iter().find(|c| col(c).is_none()) {
        let _ = writeln!(md, "**`{FILE}` is malformed:** the header lacks the column `{missing}`.\n");
        return Section { title, markdown: md, summary: vec![("5. Renders".into(), format!("renders.tsv malformed (no `{missing}` column)"), "—".into())], seconds: 0.0 };
    }
    struct Row {
        scene: String,
        medium: String,
        spp: String,
        time: f64,
        mse: f64,
        image: Option<String>,
        notes: String,
    }
    let mut rows = Vec::new();
    let mut bad = Vec::new();
    for (ln, line) in lines.enumerate() {
        let f: Vec<&str> = line.split('\t').map(str::trim).collect();
        let get = |name: &str| col(name).and_then(|i| f.get(i)).map(|s| s.to_string()).unwrap_or_default();
        match (get("time_s").parse::<f64>(), get("mse").parse::<f64>()) {
            (Ok(time), Ok(mse)) => rows.push(Row {
                scene: get("scene"),
                medium: get("medium"),
                spp: get("spp"),
                time,
                mse,
                image: Some(get("image")).filter(|s| !s.is_empty()),
                notes: get("notes"),
            }),
            _ => bad.push(ln + 2),
        }
    }
    let table: Vec<Vec<String>> =
        rows.iter().map(|r| vec![r.scene.clone(), r.medium.clone(), r.spp.clone(), format!("{:.2}", r.time), format!("{:.4e}", r.mse), r.notes.clone()]).collect();
    let _ = writeln!(md, "{}", md_table(&["scene", "medium", "spp", "time (s)", "MSE", "notes"], &table));
    if !bad.is_empty() {
        let _ = writeln!(md, "Rows skipped (unparsable `time_s` or `mse`): data lines {:?}.\n", bad);
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
                headline.push(format!("equal spp ({}): macrofacet {:.2}× faster, MSE {:.2e} vs {:.2e}", g.spp, g.time / m.time, m.mse, g.mse));
            } else if (m.time / g.time - 1.0).abs() <= 0.15 {
                derived.push(vec![g.scene.clone(), format!("equal time ({} vs {} spp)", m.spp, g.spp), format!("{:.2} s vs {:.2} s", m.time, g.time), format!("{:.2e} vs {:.2e}", m.mse, g.mse), format!("macrofacet MSE {:.2}× lower", g.mse / m.mse)]);
                headline.push(format!("equal time ({:.0} s): macrofacet MSE {:.1}× lower", g.time, g.mse / m.mse));
            }
        }
    }
    if !derived.is_empty() {
        let _ = writeln!(md, "{}", md_table(&["scene", "comparison", "time: macrofacet vs gpis", "MSE: macrofacet vs gpis", "result"], &derived));
    }
    // Bias floor: does the MSE of a medium fall like 1/spp across its rows?
    let mut groups: BTreeMap<(String, String), Vec<(f64, f64)>> = BTreeMap::new();
    for r in &rows {
        if let Ok(spp) = r.spp.parse::<f64>() {
            groups.entry((r.scene.clone(), r.medium.to_ascii_lowercase())).or_default().push((spp, r.mse));
        }
    }
    for ((scene, medium), v) in &groups {
        if v.len() < 2 {
            continue;
        }
        let lo = v.iter().cloned().fold((f64::INFINITY, 0.0), |a, b| if b.0 < a.0 { b } else { a });
        let hi = v.iter().cloned().fold((0.0, 0.0), |a, b| if b.0 > a.0 { b } else { a });
        let spp_ratio = hi.0 / lo.0;
        let mse_ratio = lo.1 / hi.1;
        let note = if mse_ratio < 0.5 * spp_ratio {
            format!(
                "falls only {mse_ratio:.1}× for {spp_ratio:.0}× the samples: it is dominated by a floor of ≈ {:.1e} (bias: \
                 the model difference plus the reference's own noise), so it measures agreement, not convergence speed",
                hi.1
            )
        } else {
            format!("falls {mse_ratio:.1}× for {spp_ratio:.0}× the samples (variance-dominated)")
        };
        let _ = writeln!(md, "- `{scene}`, {medium}: the MSE {note}.\n");
        if mse_ratio < 0.5 * spp_ratio {
            headline.push(format!("{medium} MSE vs the reference has a bias floor ≈ {:.1e}", hi.1));
        }
    }
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
