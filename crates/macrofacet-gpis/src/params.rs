//! The gpis ground truth built by named parameters: the same names as the macrofacet medium
//! ([`macrofacet::params`]), so a scene switches method by changing only the type, and the
//! domain of the parameters that only a gpis takes.

use crate::{GpisSurface, MarchSettings, Memory, SeKernel};
use macrofacet::error::{Error, ErrorKind, Result};
use macrofacet::limits::{check_range, out_of_domain, SHELL_EXTENT_RANGE};
use macrofacet::params::{invalid_choice, read_conductor, read_roughness, read_sigma, ParamSet, Reader};

/// `shell_extent` of a gpis: its band `±kσ`. The march starts sampling at `kσ` above the mean,
/// where the process is already inside with probability `Φ(−k)`: 0.13 % at 3 (the medium's own
/// default cut), 16 % at 1, so a smaller band is no ground truth.
pub const GPIS_BAND_RANGE: (f64, f64) = (3.0, SHELL_EXTENT_RANGE.1);

/// A gpis's `shell_extent` (its band) within [`GPIS_BAND_RANGE`].
pub fn check_gpis_band(k: f64) -> Result<f64> {
    check_range("parameter \"shell_extent\" (the gpis band)", k, GPIS_BAND_RANGE, "a narrower band misses the crossings above it")
}

/// Most samples a gpis march may take to cross its band `±kσ` along the normal: the march of
/// one segment costs `O(window²)` per sample (about 0.6 µs), and rays at 84° from the normal
/// must still cross within [`MarchSettings::max_points`] (1e5) samples.
pub const GPIS_MAX_BAND_SAMPLES: f64 = 1e4;

/// Refuses gpis parameters whose march would take more than [`GPIS_MAX_BAND_SAMPLES`] samples to
/// cross the band at normal incidence: `2kσ/Δt` with the step `Δt = l sqrt(−2 ln ρ)` along the
/// roughest axis, `l = √2 σ/α_max` (seeds/000 Eq. 4), capped at `σ` (issue 9 item 13: `α = 1e5`
/// took over 20 s for 16² pixels).
pub fn check_march_length(settings: &MarchSettings, alpha: [f64; 3]) -> Result<()> {
    let alpha_max = alpha.iter().copied().fold(0.0, f64::max);
    let step_over_sigma = (std::f64::consts::SQRT_2 / alpha_max * (-2.0 * settings.step_correlation.ln()).sqrt()).min(settings.max_step);
    let samples = 2.0 * settings.envelope / step_over_sigma;
    if samples <= GPIS_MAX_BAND_SAMPLES {
        Ok(())
    } else {
        Err(out_of_domain(format!(
            "a gpis march across the band of \"shell_extent\" = {} sigma would take {samples:.3e} samples (largest roughness {alpha_max:e}, \
             \"step_correlation\" = {}), more than {GPIS_MAX_BAND_SAMPLES:e}: lower the roughness (or raise the lengthscales), \
             \"shell_extent\" or \"step_correlation\"",
            settings.envelope, settings.step_correlation
        )))
    }
}

/// Builds the realization-based GPIS ground truth (seeds/004) from the macrofacet medium's
/// parameter names, so that a scene switches method by changing only the type:
/// `sigma`/`variance`, `shell_extent` (the band `±kσ` of the mean surface where realizations are
/// sampled; default 6 for the ground truth), `distribution` (`gpss`, or `beckmann` = height-field
/// kernel `l_z = ∞`; `ggx` is not a Gaussian-process kernel), the roughness or kernel form,
/// `material`/`eta`/`k`/`specular_reflectance`, plus `memory` (`renewal` or `renewal_plus`,
/// default `renewal_plus`) and `step_correlation` (in (0, 1), default 0.95). Parameters that only
/// concern the statistical medium (`micro_bsdf` other than `conductor`, `vndf_sampling`,
/// `mixture_ratio`, `reflectance`) are errors.
pub fn gpis_from_params(params: &ParamSet) -> Result<GpisSurface> {
    let r = Reader::new(params);
    let sigma = read_sigma(&r)?;
    let mut settings = MarchSettings::default();
    if let Some(k) = r.float("shell_extent")? {
        settings.envelope = check_gpis_band(k)?;
    }
    if let Some(rho) = r.float("step_correlation")? {
        if !(rho > 0.0 && rho < 1.0) {
            return Err(Error::new(ErrorKind::InvalidValue, format!("parameter \"step_correlation\" must lie in (0, 1), got {rho}")));
        }
        settings.step_correlation = rho;
    }
    let height_field = match r.string("distribution")?.unwrap_or("gpss") {
        "gpss" => false,
        "beckmann" => true,
        "ggx" => {
            return Err(Error::new(ErrorKind::InvalidValue,
                "distribution \"ggx\" has no Gaussian-process kernel: a gpis medium takes \"gpss\" or \"beckmann\""))
        }
        other => return Err(invalid_choice("distribution", other, "\"gpss\", \"beckmann\"")),
    };
    let alpha = read_roughness(&r, sigma, !height_field)?;
    check_march_length(&settings, alpha)?;
    let kernel = SeKernel::from_roughness(sigma, glam::DVec3::from_array(alpha))?;
    let memory = match r.string("memory")?.unwrap_or("renewal_plus") {
        "renewal" => Memory::Renewal,
        "renewal_plus" => Memory::RenewalPlus,
        other => return Err(invalid_choice("memory", other, "\"renewal\", \"renewal_plus\"")),
    };
    let micro_bsdf = match r.string("micro_bsdf")?.unwrap_or("conductor") {
        "conductor" => read_conductor(&r)?,
        other => return Err(invalid_choice("micro_bsdf", other, "\"conductor\" (a gpis surface reflects specularly)")),
    };
    r.finish()?;
    Ok(GpisSurface { kernel, memory, settings, micro_bsdf })
}
