//! Fresnel reflectance of conductors with a complex index of refraction `eta + i k`, per RGB
//! channel, and named presets for common metals.

use crate::Rgb;

/// Unpolarised reflectance of a conductor, the exact closed form for a complex index
/// `eta + i k` relative to the outside medium (Born & Wolf, Sec. 14.2; the usual rendering
/// arrangement of it in terms of `a² + b²`). `cos_i` is clamped to `[0, 1]`.
///
/// With `a + i b = sqrt(eta² − k² − sin² + 2i eta k)`, the usual
/// `R_s = (a² + b² + cos² − 2a cos) / (a² + b² + cos² + 2a cos)` is written as
/// `((a − cos)² + b²) / ((a + cos)² + b²)`, and `R_p / R_s` likewise as
/// `((a cos − sin²)² + b² cos²) / ((a cos + sin²)² + b² cos²)`: sums of squares, so the result lies
/// in `[0, 1]` by construction. The difference form cancels to a negative reflectance near
/// `eta = 1, k = 0` (found by fuzzing: a weight of −4.6e-17).
pub fn fresnel_conductor(cos_i: f64, eta: f64, k: f64) -> f64 {
    let c = cos_i.clamp(0.0, 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let (eta2, k2) = (eta * eta, k * k);
    let t0 = eta2 - k2 - s2;
    let a2_plus_b2 = (t0 * t0 + 4.0 * eta2 * k2).sqrt();
    // a² and b² are halves of (a² + b²) ± t0, both >= 0; rounding may leave a hair below.
    let a = (0.5 * (a2_plus_b2 + t0)).max(0.0).sqrt();
    let b2 = (0.5 * (a2_plus_b2 - t0)).max(0.0);
    let rs_denominator = (a + c).powi(2) + b2;
    if rs_denominator == 0.0 {
        return 0.0; // eta = 1, k = 0 at grazing incidence: no interface, no reflection
    }
    let rs = ((a - c).powi(2) + b2) / rs_denominator;
    let (ac, b2c2) = (a * c, b2 * c2);
    let rp_denominator = (ac + s2).powi(2) + b2c2;
    // 0 only at normal incidence (s2 = 0) with a = b = 0 (eta = k = 0), where R_p = R_s.
    let rp_over_rs = if rp_denominator == 0.0 { 1.0 } else { ((ac - s2).powi(2) + b2c2) / rp_denominator };
    0.5 * rs * (1.0 + rp_over_rs)
}

/// [`fresnel_conductor`] per channel.
pub fn fresnel_conductor_rgb(cos_i: f64, eta: Rgb, k: Rgb) -> Rgb {
    [0, 1, 2].map(|c| fresnel_conductor(cos_i, eta[c], k[c]))
}

/// A metal's complex index of refraction reduced to linear-sRGB channels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConductorPreset {
    pub name: &'static str,
    pub eta: Rgb,
    pub k: Rgb,
}

/// Named conductors, accepted by the `"material"` parameter (Mitsuba 3 uses the same names).
///
/// Source: measured spectral complex indices of refraction (Palik, *Handbook of Optical
/// Constants of Solids*, 1985) converted to linear sRGB, as tabulated in Tungsten's
/// `ComplexIorData.hpp` (B. Bitterli) — the triplets in common use by RGB renderers; `mfrender`'s
/// independent `roughconductor` uses the same table, so the thin-shell comparison sees the same
/// metal. `"none"` is handled separately as a perfect mirror (reflectance 1), as in Mitsuba.
pub const CONDUCTOR_PRESETS: &[ConductorPreset] = &[
    ConductorPreset { name: "Ag", eta: [0.1552646489, 0.1167232965, 0.1383806959], k: [4.8283433224, 3.1222459278, 2.1469504455] },
    ConductorPreset { name: "Al", eta: [1.6574599595, 0.8803689579, 0.5212287346], k: [9.2238691996, 6.2695232477, 4.8370012281] },
    ConductorPreset { name: "Au", eta: [0.1431189557, 0.3749570432, 1.4424785571], k: [3.9831604247, 2.3857207478, 1.6032152899] },
    ConductorPreset { name: "Cr", eta: [4.3696828663, 2.9167024892, 1.6547005413], k: [5.2064337956, 4.2313645277, 3.7549467933] },
    ConductorPreset { name: "Cu", eta: [0.2004376970, 0.9240334304, 1.1022119527], k: [3.9129485033, 2.4528477015, 2.1421879552] },
];

/// Looks a preset up by name (case-sensitive, as in Mitsuba).
pub fn conductor_preset(name: &str) -> Option<&'static ConductorPreset> {
    CONDUCTOR_PRESETS.iter().find(|p| p.name == name)
}
