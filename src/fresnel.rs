//! Fresnel reflectance of conductors with a complex index of refraction `eta + i k`, per RGB
//! channel, and named presets for common metals.

use crate::Rgb;

/// Unpolarised reflectance of a conductor, the exact closed form for a complex index
/// `eta + i k` relative to the outside medium (Born & Wolf, Sec. 14.2; the usual rendering
/// arrangement of it in terms of `a² + b²`). `cos_i` is clamped to `[0, 1]`.
pub fn fresnel_conductor(cos_i: f64, eta: f64, k: f64) -> f64 {
    let c = cos_i.clamp(0.0, 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let eta2 = eta * eta;
    let k2 = k * k;
    let t0 = eta2 - k2 - s2;
    let a2_plus_b2 = (t0 * t0 + 4.0 * eta2 * k2).sqrt();
    let a = (0.5 * (a2_plus_b2 + t0)).max(0.0).sqrt();
    let t1 = a2_plus_b2 + c2;
    let t2 = 2.0 * c * a;
    let rs = (t1 - t2) / (t1 + t2);
    let t3 = c2 * a2_plus_b2 + s2 * s2;
    let t4 = t2 * s2;
    let rp = rs * (t3 - t4) / (t3 + t4);
    0.5 * (rs + rp)
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
    ConductorPreset { name: "Ag", eta: [0.155265, 0.116723, 0.138342], k: [4.828181, 3.122249, 2.146961] },
    ConductorPreset { name: "Al", eta: [1.657460, 0.880369, 0.521229], k: [9.223869, 6.269523, 4.837001] },
    ConductorPreset { name: "Au", eta: [0.143119, 0.374957, 1.442479], k: [3.983160, 2.385721, 1.603215] },
    ConductorPreset { name: "Cr", eta: [4.368240, 2.914183, 1.654774], k: [5.203870, 4.231365, 3.754947] },
    ConductorPreset { name: "Cu", eta: [0.200438, 0.924033, 1.102212], k: [3.912949, 2.452848, 2.142188] },
];

/// Looks a preset up by name (case-sensitive, as in Mitsuba).
pub fn conductor_preset(name: &str) -> Option<&'static ConductorPreset> {
    CONDUCTOR_PRESETS.iter().find(|p| p.name == name)
}
