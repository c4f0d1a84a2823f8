//! Shared plumbing: the run context, a deterministic parallel map, running means with standard
//! errors, Markdown tables and CSV files.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// Command-line settings shared by every section.
pub struct Ctx {
    pub out: PathBuf,
    pub quick: bool,
    pub threads: usize,
}

impl Ctx {
    /// Writes `DIR/data/name` (CSV) and returns its path relative to `DIR`.
    pub fn write_csv(&self, name: &str, header: &str, rows: &[String]) -> String {
        let dir = self.out.join("data");
        std::fs::create_dir_all(&dir).expect("create data directory");
        let mut s = String::from(header);
        s.push('\n');
        for r in rows {
            s.push_str(r);
            s.push('\n');
        }
        std::fs::write(dir.join(name), s).expect("write csv");
        format!("data/{name}")
    }
}

/// What a section hands back to the report.
pub struct Section {
    pub title: String,
    pub markdown: String,
    /// One line per comparison for the summary table: (comparison, headline, verdict).
    pub summary: Vec<(String, String, String)>,
    pub seconds: f64,
}

/// `f` over `jobs` on `threads` threads; results in job order. Each job must seed its own
/// generator, so the output does not depend on the schedule or the thread count.
pub fn par_map<J: Sync, R: Send>(jobs: &[J], threads: usize, f: impl Fn(&J) -> R + Sync) -> Vec<R> {
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<R>>> = Mutex::new((0..jobs.len()).map(|_| None).collect());
    std::thread::scope(|scope| {
        for _ in 0..threads.max(1) {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                if i >= jobs.len() {
                    break;
                }
                let r = f(&jobs[i]);
                results.lock().unwrap()[i] = Some(r);
            });
        }
    });
    results.into_inner().unwrap().into_iter().map(|r| r.expect("job finished")).collect()
}

/// Running sums for the mean and standard error of an RGB estimator.
#[derive(Clone, Copy, Debug, Default)]
pub struct Acc3 {
    pub n: f64,
    pub sum: [f64; 3],
    pub sum2: [f64; 3],
    /// Sums of the channel average `(R + G + B)/3` and of its square.
    pub gsum: f64,
    pub gsum2: f64,
}

impl Acc3 {
    pub fn add(&mut self, v: [f64; 3]) {
        self.n += 1.0;
        for c in 0..3 {
            self.sum[c] += v[c];
            self.sum2[c] += v[c] * v[c];
        }
        let g = (v[0] + v[1] + v[2]) / 3.0;
        self.gsum += g;
        self.gsum2 += g * g;
    }
    pub fn merge(&mut self, o: &Acc3) {
        self.n += o.n;
        for c in 0..3 {
            self.sum[c] += o.sum[c];
            self.sum2[c] += o.sum2[c];
        }
        self.gsum += o.gsum;
        self.gsum2 += o.gsum2;
    }
    pub fn mean(&self) -> [f64; 3] {
        self.sum.map(|s| s / self.n.max(1.0))
    }
    /// Standard error of the mean, per channel.
    pub fn se(&self) -> [f64; 3] {
        let n = self.n.max(2.0);
        [0, 1, 2].map(|c| {
            let m = self.sum[c] / n;
            ((self.sum2[c] / n - m * m).max(0.0) / (n - 1.0)).sqrt()
        })
    }
    /// Mean and standard error of the channel average `(R + G + B)/3`.
    pub fn grey(&self) -> (f64, f64) {
        let n = self.n.max(2.0);
        let m = self.gsum / n;
        (m, ((self.gsum2 / n - m * m).max(0.0) / (n - 1.0)).sqrt())
    }
}

/// A Markdown table.
/// A Markdown table; `|` inside a cell is escaped.
pub fn md_table(header: &[&str], rows: &[Vec<String>]) -> String {
    let esc = |c: &str| c.replace('|', "\\|");
    let mut s = String::new();
    let _ = writeln!(s, "| {} |", header.iter().map(|h| esc(h)).collect::<Vec<_>>().join(" | "));
    let _ = writeln!(s, "|{}|", header.iter().map(|_| "---").collect::<Vec<_>>().join("|"));
    for r in rows {
        let _ = writeln!(s, "| {} |", r.iter().map(|c| esc(c)).collect::<Vec<_>>().join(" | "));
    }
    s
}

/// Runs a section body and records its wall time.
pub fn timed(f: impl FnOnce() -> Section) -> Section {
    let start = Instant::now();
    let mut s = f();
    s.seconds = start.elapsed().as_secs_f64();
    s
}

/// Unit direction of propagation at `theta_deg` from the downward normal, in the xz-plane
/// (travelling toward +x).
pub fn downward(theta_deg: f64) -> glam::DVec3 {
    let t = theta_deg.to_radians();
    glam::DVec3::new(t.sin(), 0.0, -t.cos())
}

pub fn yes_no(ok: bool) -> String {
    if ok { "yes".into() } else { "**NO**".into() }
}

/// The two GPSS kernels the realization comparisons use (σ = 1, α = 1), each with the NDF the
/// macrofacet model gives it: the height field (`l_z = ∞`) ↔ Beckmann, the isotropic kernel ↔ the
/// generalized macrofacet with `α_z = α`.
pub struct KernelCase {
    pub label: &'static str,
    pub file: &'static str,
    pub kernel: macrofacet_gpis::SeKernel,
    pub ndf: macrofacet::ndf::Ndf,
    pub ndf_label: &'static str,
}

pub fn kernel_cases() -> Vec<KernelCase> {
    use glam::DVec3;
    use macrofacet_gpis::SeKernel;
    use macrofacet::ndf::{Beckmann, Gpss, Ndf};
    vec![
        KernelCase {
            label: "height field (l_z = ∞)",
            file: "height_field",
            kernel: SeKernel::from_roughness(1.0, DVec3::new(1.0, 1.0, 0.0)).unwrap(),
            ndf: Ndf::Beckmann(Beckmann::new(1.0, 1.0).unwrap()),
            ndf_label: "Beckmann α = 1 (= gpss α_z = 0)",
        },
        KernelCase {
            label: "isotropic (l_x = l_y = l_z)",
            file: "isotropic",
            kernel: SeKernel::from_roughness(1.0, DVec3::ONE).unwrap(),
            ndf: Ndf::Gpss(Gpss::new(1.0, 1.0, 1.0).unwrap()),
            ndf_label: "gpss α = α_z = 1",
        },
    ]
}
