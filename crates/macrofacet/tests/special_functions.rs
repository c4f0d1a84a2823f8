//! Accuracy and edge-case tests for `macrofacet::special`.
//!
//! The reference values in `tests/data/special_reference.csv` come from mpmath at 50 digits
//! (`python3 tools/special_reference.py` regenerates them; see that script for the formulas).

use macrofacet::special::*;

const REFERENCE: &str = include_str!("data/special_reference.csv");

/// Required relative accuracy against the 50-digit references.
const REL_TOL: f64 = 1e-12;
/// References below the normal range (subnormal or zero) are compared absolutely: the functions
/// are only required to be accurate "until they underflow".
const ABS_TOL_UNDERFLOW: f64 = f64::MIN_POSITIVE;
/// `probit` near `p = ½` (result ≈ 0) is only required to be absolutely accurate.
const ABS_TOL_PROBIT_CENTRE: f64 = 1e-15;

fn eval(name: &str, x: f64) -> f64 {
    match name {
        "erf" => erf(x),
        "erfc" => erfc(x),
        "erfcx" => erfcx(x),
        "normal_pdf" => normal_pdf(x),
        "normal_cdf" => normal_cdf(x),
        "ln_normal_cdf" => ln_normal_cdf(x),
        "normal_pdf_over_cdf" => normal_pdf_over_cdf(x),
        "probit" => probit(x),
        "probit_of_ln" => probit_of_ln(x),
        other => panic!("unknown function {other} in reference CSV"),
    }
}

struct Row {
    name: String,
    x: f64,
    want: f64,
}

fn rows() -> Vec<Row> {
    REFERENCE
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("function,") && !l.trim().is_empty())
        .map(|l| {
            let mut it = l.split(',');
            let name = it.next().expect("name").to_string();
            let x: f64 = it.next().expect("x").parse().expect("x parses");
            let want: f64 = it.next().expect("want").parse().expect("want parses");
            Row { name, x, want }
        })
        .collect()
}

/// Relative error, with exact matches (including infinities and zeros) giving 0.
fn rel_err(got: f64, want: f64) -> f64 {
    if got == want {
        0.0
    } else if want == 0.0 || want.is_infinite() || got.is_nan() {
        f64::INFINITY
    } else {
        ((got - want) / want).abs()
    }
}

fn acceptable(name: &str, got: f64, want: f64) -> bool {
    if rel_err(got, want) <= REL_TOL {
        return true;
    }
    if !got.is_finite() || !want.is_finite() {
        return false;
    }
    let abs = (got - want).abs();
    (want.abs() < f64::MIN_POSITIVE && abs <= ABS_TOL_UNDERFLOW)
        || (name == "probit" && want.abs() < 1e-3 && abs <= ABS_TOL_PROBIT_CENTRE)
}

#[test]
fn matches_mpmath_references() {
    let rows = rows();
    assert!(
        rows.len() > 500,
        "reference CSV has only {} rows",
        rows.len()
    );

    let names = [
        "erf",
        "erfc",
        "erfcx",
        "normal_pdf",
        "normal_cdf",
        "ln_normal_cdf",
        "normal_pdf_over_cdf",
        "probit",
        "probit_of_ln",
    ];
    let mut failures = Vec::new();
    for name in names {
        let mut worst: Option<(f64, f64, f64, f64)> = None; // (rel, x, got, want)
        let mut count = 0;
        let mut absolute = 0;
        for r in rows.iter().filter(|r| r.name == name) {
            count += 1;
            let got = eval(name, r.x);
            // Points compared absolutely do not count towards the relative worst case.
            let rel = if rel_err(got, r.want) > REL_TOL && acceptable(name, got, r.want) {
                absolute += 1;
                0.0
            } else {
                rel_err(got, r.want)
            };
            if worst.map_or(true, |w| rel > w.0) {
                worst = Some((rel, r.x, got, r.want));
            }
            if !acceptable(name, got, r.want) {
                failures.push(format!(
                    "{name}({:e}) = {got:e}, want {:e}, rel err {:e}",
                    r.x,
                    r.want,
                    rel_err(got, r.want)
                ));
            }
        }
        assert!(count > 0, "no reference rows for {name}");
        let (rel, x, got, want) = worst.unwrap();
        println!(
            "{name:>20}: {count:4} points ({absolute} compared absolutely), worst rel err {rel:.2e} \
             at x = {x:e} (got {got:e}, want {want:e})"
        );
    }
    assert!(
        failures.is_empty(),
        "{} reference points out of tolerance:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn nan_in_nan_out() {
    type NamedFunction = (&'static str, fn(f64) -> f64);
    let fs: [NamedFunction; 9] = [
        ("erf", erf),
        ("erfc", erfc),
        ("erfcx", erfcx),
        ("normal_pdf", normal_pdf),
        ("normal_cdf", normal_cdf),
        ("ln_normal_cdf", ln_normal_cdf),
        ("normal_pdf_over_cdf", normal_pdf_over_cdf),
        ("probit", probit),
        ("probit_of_ln", probit_of_ln),
    ];
    for (name, f) in fs {
        assert!(f(f64::NAN).is_nan(), "{name}(NaN) is not NaN");
        assert!(f(-f64::NAN).is_nan(), "{name}(-NaN) is not NaN");
    }
}

#[test]
fn infinities_and_limits() {
    let inf = f64::INFINITY;
    assert_eq!(erf(inf), 1.0);
    assert_eq!(erf(-inf), -1.0);
    assert_eq!(erfc(inf), 0.0);
    assert_eq!(erfc(-inf), 2.0);

    assert_eq!(erfcx(inf), 0.0);
    assert_eq!(erfcx(-inf), inf);
    // The true value overflows f64 below x ≈ −26.64.
    assert_eq!(erfcx(-27.0), inf);
    assert!(erfcx(-26.6).is_finite());
    // Never underflows spuriously for large x: ≈ 1/(x√π).
    let big = 1e300;
    assert!((erfcx(big) * big * std::f64::consts::PI.sqrt() - 1.0).abs() < 1e-15);
    assert!(erfcx(f64::MAX) > 0.0);

    assert_eq!(normal_pdf(inf), 0.0);
    assert_eq!(normal_pdf(-inf), 0.0);
    assert_eq!(normal_cdf(inf), 1.0);
    assert_eq!(normal_cdf(-inf), 0.0);

    assert_eq!(ln_normal_cdf(inf), 0.0);
    assert_eq!(ln_normal_cdf(-inf), -inf);
    assert!(ln_normal_cdf(-1e150).is_finite());
    assert_eq!(ln_normal_cdf(-f64::MAX), -inf); // −x²/2 overflows

    assert_eq!(normal_pdf_over_cdf(inf), 0.0);
    assert_eq!(normal_pdf_over_cdf(-inf), inf);
    // ρ(x) ~ −x for x → −∞, even where φ and Φ both underflow.
    assert!((normal_pdf_over_cdf(-1e300) / 1e300 - 1.0).abs() < 1e-15);

    assert_eq!(probit(0.0), -inf);
    assert_eq!(probit(-0.0), -inf);
    assert_eq!(probit(1.0), inf);
    for p in [-1e-300, -0.5, 1.0 + f64::EPSILON, 2.0, inf, -inf] {
        assert!(probit(p).is_nan(), "probit({p}) should be NaN");
    }
    assert_eq!(probit(0.5), 0.0);
    assert!(probit(f64::from_bits(1)).is_finite()); // smallest subnormal

    assert_eq!(probit_of_ln(0.0), inf);
    assert_eq!(probit_of_ln(-0.0), inf);
    assert_eq!(probit_of_ln(-inf), -inf);
    for l in [1e-300, 1.0, inf] {
        assert!(probit_of_ln(l).is_nan(), "probit_of_ln({l}) should be NaN");
    }
    let x = probit_of_ln(-f64::MAX);
    assert!(x.is_finite() && x < -1.8e154, "probit_of_ln(-MAX) = {x}");
}

#[test]
fn no_panics_on_awkward_inputs() {
    let xs = [
        0.0,
        -0.0,
        f64::MIN_POSITIVE,
        -f64::MIN_POSITIVE,
        f64::from_bits(1),
        f64::MAX,
        f64::MIN,
        f64::EPSILON,
        1.0 - f64::EPSILON / 2.0,
        0.5,
        -0.5,
        26.0,
        -26.0,
        38.5,
        -38.5,
        1e154,
        -1e154,
    ];
    for x in xs {
        let _ = (
            erf(x),
            erfc(x),
            erfcx(x),
            normal_pdf(x),
            normal_cdf(x),
            ln_normal_cdf(x),
            normal_pdf_over_cdf(x),
            probit(x),
            probit_of_ln(x),
        );
        assert!(!normal_pdf_over_cdf(x).is_nan(), "rho({x}) is NaN");
        assert!(!ln_normal_cdf(x).is_nan(), "ln Phi({x}) is NaN");
    }
}

#[test]
fn probit_is_monotone() {
    // Dense uniform grid plus both tails on a log grid.
    let mut ps: Vec<f64> = (1..200_000).map(|i| i as f64 / 200_000.0).collect();
    ps.extend((0..3000).map(|i| 10f64.powf(-320.0 + i as f64 * 0.1)));
    ps.extend((0..1600).map(|i| 1.0 - 10f64.powf(-16.0 + i as f64 * 0.01)));
    ps.retain(|p| *p > 0.0 && *p < 1.0);
    ps.sort_by(f64::total_cmp);
    ps.dedup();
    let xs: Vec<f64> = ps.iter().map(|&p| probit(p)).collect();
    for i in 1..xs.len() {
        assert!(
            xs[i] >= xs[i - 1],
            "probit not monotone: probit({:e}) = {:e} < probit({:e}) = {:e}",
            ps[i],
            xs[i],
            ps[i - 1],
            xs[i - 1]
        );
    }
    // Spacing of adjacent doubles near ½: strictly increasing there.
    let mut p = 0.5 - 64.0 * f64::EPSILON;
    let mut prev = probit(p);
    for _ in 0..200 {
        p = f64::from_bits(p.to_bits() + 1);
        let x = probit(p);
        assert!(x > prev, "probit not strictly increasing at {p:e}");
        prev = x;
    }
}

#[test]
fn ln_normal_cdf_and_probit_of_ln_are_monotone() {
    let xs: Vec<f64> = (0..400_000)
        .map(|i| -1000.0 + i as f64 * (1040.0 / 400_000.0))
        .collect();
    let ys: Vec<f64> = xs.iter().map(|&x| ln_normal_cdf(x)).collect();
    for i in 1..ys.len() {
        assert!(
            ys[i] >= ys[i - 1],
            "ln_normal_cdf not monotone at x = {:e}: {:e} < {:e}",
            xs[i],
            ys[i],
            ys[i - 1]
        );
    }
    // probit_of_ln on a log grid of −ln p from 1e-18 to 1e300 (descending ln p ⇒ descending x).
    let ls: Vec<f64> = (0..31_800)
        .map(|i| -(10f64.powf(-18.0 + i as f64 * 0.01)))
        .collect();
    let qs: Vec<f64> = ls.iter().map(|&l| probit_of_ln(l)).collect();
    for i in 1..qs.len() {
        assert!(
            qs[i] <= qs[i - 1],
            "probit_of_ln not monotone at ln p = {:e}: {:e} > {:e}",
            ls[i],
            qs[i],
            qs[i - 1]
        );
    }
}

#[test]
fn round_trips() {
    // ln Φ(Φ⁻¹(e^l)) = l over twenty decades of −l each side of 1.
    let mut worst = 0.0_f64;
    let mut worst_at = 0.0;
    for i in 0..=3000 {
        let l = -(10f64.powf(-18.0 + i as f64 * 0.01));
        let back = ln_normal_cdf(probit_of_ln(l));
        let rel = ((back - l) / l).abs();
        // Condition number of l ↦ Φ⁻¹ ↦ ln Φ: x ρ(x)/|ln Φ(x)|, at most ~x² ≈ 80 here.
        if rel > worst {
            worst = rel;
            worst_at = l;
        }
    }
    assert!(
        worst < 1e-12,
        "ln_normal_cdf(probit_of_ln(l)) worst rel err {worst:e} at l = {worst_at:e}"
    );

    // Φ(Φ⁻¹(p)) = p in the lower half (relative) and Φ⁻¹(1 − p) = −Φ⁻¹(p).
    for i in 0..3000 {
        let p = 10f64.powf(-300.0 + i as f64 * 0.1);
        if p > 0.5 {
            break;
        }
        let x = probit(p);
        let back = normal_cdf(x);
        // d ln Φ = ρ dx, relative error of x ~ 1 ulp ⇒ relative error of Φ ~ x ρ ε ≲ x² ε.
        let tol = 1e-15 * (4.0 + x * x);
        assert!(
            ((back - p) / p).abs() < tol,
            "normal_cdf(probit({p:e})) = {back:e}"
        );
        let q = 1.0 - p;
        if 1.0 - q == p {
            assert_eq!(probit(q), -x, "probit symmetry at p = {p:e}");
        }
    }
    // probit and probit_of_ln agree where both are meaningful.
    for i in 1..1000 {
        let p = i as f64 / 1000.0;
        let a = probit(p);
        let b = probit_of_ln(p.ln());
        assert!(
            (a - b).abs() <= 1e-14 * (1.0 + a.abs()),
            "p = {p}: {a} vs {b}"
        );
    }
}
