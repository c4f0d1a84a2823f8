//! Construction by named parameters, Mitsuba style, so that the same names work in a scene file,
//! in the C ABI (`mf_params_*`) and from Rust. Unknown names, wrong types, missing or
//! contradictory parameters and out-of-range values are errors naming the parameter.
//!
//! The names, their types, ranges and defaults are documented once: the table of README.md,
//! section "Medium parameters". `scripts/check_params_doc.sh` (run by `scripts/test.sh`) fails when
//! that table and the names read here differ.

use crate::error::{check_positive, Error, ErrorKind, Result};
use crate::fresnel::conductor_preset;
use crate::height::{HeightProfile, DEFAULT_SHELL_EXTENT};
use crate::limits::{check_alpha_z, check_conductor_index, check_roughness, check_sigma};
use crate::medium::MacrofacetMedium;
use crate::ndf::{alpha_from_kernel, Beckmann, BeckmannUniformMixture, Ggx, Gpss, Gtr, GtrLambda, Ltmd, LtmdBase, Ndf, NormalUniformMixture};
use crate::phase::{MacrofacetPhase, MicroBsdf, VndfSampling};
use crate::Rgb;
use std::cell::RefCell;

/// A parameter value. A float is accepted where an RGB triplet is expected (grey).
#[derive(Clone, Debug, PartialEq)]
pub enum ParamValue {
    Float(f64),
    Rgb(Rgb),
    String(String),
}

impl ParamValue {
    fn type_name(&self) -> &'static str {
        match self {
            ParamValue::Float(_) => "float",
            ParamValue::Rgb(_) => "rgb",
            ParamValue::String(_) => "string",
        }
    }
}

/// An ordered set of named parameters. Setting a name again replaces its value.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ParamSet {
    entries: Vec<(String, ParamValue)>,
}

impl ParamSet {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn set(&mut self, name: &str, value: ParamValue) -> &mut Self {
        match self.entries.iter_mut().find(|(n, _)| n == name) {
            Some(entry) => entry.1 = value,
            None => self.entries.push((name.to_owned(), value)),
        }
        self
    }

    pub fn set_float(&mut self, name: &str, value: f64) -> &mut Self {
        self.set(name, ParamValue::Float(value))
    }

    pub fn set_rgb(&mut self, name: &str, value: Rgb) -> &mut Self {
        self.set(name, ParamValue::Rgb(value))
    }

    pub fn set_string(&mut self, name: &str, value: &str) -> &mut Self {
        self.set(name, ParamValue::String(value.to_owned()))
    }

    pub fn get(&self, name: &str) -> Option<&ParamValue> {
        self.entries.iter().find(|(n, _)| n == name).map(|(_, v)| v)
    }

    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.entries.iter().map(|(n, _)| n.as_str())
    }
}

/// Reads a [`ParamSet`] and records which names were consumed, so that leftovers are reported
/// (also by the constructors of other crates, e.g. the gpis ground truth).
pub struct Reader<'a> {
    params: &'a ParamSet,
    used: RefCell<Vec<&'a str>>,
}

impl<'a> Reader<'a> {
    pub fn new(params: &'a ParamSet) -> Self {
        Reader { params, used: RefCell::new(Vec::new()) }
    }

    pub fn take(&self, name: &str) -> Option<&'a ParamValue> {
        let (n, v) = self.params.entries.iter().find(|(n, _)| n == name)?;
        self.used.borrow_mut().push(n.as_str());
        Some(v)
    }

    fn has(&self, name: &str) -> bool {
        self.params.get(name).is_some()
    }

    fn wrong_type(name: &str, want: &str, got: &ParamValue) -> Error {
        Error::new(
            ErrorKind::WrongType,
            format!("parameter \"{name}\" must be a {want}, got a {}", got.type_name()),
        )
    }

    pub fn float(&self, name: &str) -> Result<Option<f64>> {
        match self.take(name) {
            None => Ok(None),
            Some(ParamValue::Float(x)) if x.is_finite() => Ok(Some(*x)),
            Some(ParamValue::Float(x)) => Err(Error::new(
                ErrorKind::InvalidValue,
                format!("parameter \"{name}\" must be finite, got {x}"),
            )),
            Some(v) => Err(Self::wrong_type(name, "float", v)),
        }
    }

    pub fn rgb(&self, name: &str) -> Result<Option<Rgb>> {
        let rgb = match self.take(name) {
            None => return Ok(None),
            Some(ParamValue::Float(x)) => [*x; 3],
            Some(ParamValue::Rgb(c)) => *c,
            Some(v) => return Err(Self::wrong_type(name, "rgb or float", v)),
        };
        if rgb.iter().all(|c| c.is_finite() && *c >= 0.0) {
            Ok(Some(rgb))
        } else {
            Err(Error::new(
                ErrorKind::InvalidValue,
                format!("parameter \"{name}\" must be finite and >= 0, got {rgb:?}"),
            ))
        }
    }

    pub fn unit_rgb(&self, name: &str, default: f64) -> Result<Rgb> {
        let rgb = self.rgb(name)?.unwrap_or([default; 3]);
        if rgb.iter().all(|c| *c <= 1.0) {
            Ok(rgb)
        } else {
            Err(Error::new(
                ErrorKind::InvalidValue,
                format!("parameter \"{name}\" must lie in [0, 1] (energy conservation), got {rgb:?}"),
            ))
        }
    }

    pub fn string(&self, name: &str) -> Result<Option<&'a str>> {
        match self.take(name) {
            None => Ok(None),
            Some(ParamValue::String(s)) => Ok(Some(s.as_str())),
            Some(v) => Err(Self::wrong_type(name, "string", v)),
        }
    }

    /// Fails on any name that was not consumed.
    pub fn finish(&self) -> Result<()> {
        let used = self.used.borrow();
        match self.params.names().find(|n| !used.contains(n)) {
            None => Ok(()),
            Some(n) => Err(Error::new(
                ErrorKind::UnknownParameter,
                format!("unknown parameter \"{n}\" (or not applicable to the chosen options)"),
            )),
        }
    }
}

pub fn missing(message: String) -> Error {
    Error::new(ErrorKind::MissingParameter, message)
}

pub fn invalid_choice(name: &str, got: &str, choices: &str) -> Error {
    Error::new(ErrorKind::InvalidValue, format!("parameter \"{name}\" must be one of {choices}, got \"{got}\""))
}

/// Builds a macrofacet medium from named parameters (README.md "Medium parameters").
pub fn medium_from_params(params: &ParamSet) -> Result<MacrofacetMedium> {
    let r = Reader::new(params);

    let sigma = read_sigma(&r)?;
    let shell_extent = r.float("shell_extent")?.unwrap_or(DEFAULT_SHELL_EXTENT);
    let height = HeightProfile::new(sigma, shell_extent)
        .map_err(|e| Error::new(e.kind, e.message))?;

    let (ndf, alpha_mean) = read_ndf(&r, Some(sigma), "gpss")?;

    let micro_bsdf = match r.string("micro_bsdf")?.unwrap_or("conductor") {
        "conductor" => read_conductor(&r)?,
        "diffuse" => MicroBsdf::Diffuse { reflectance: r.unit_rgb("reflectance", 0.5)? },
        other => return Err(invalid_choice("micro_bsdf", other, "\"conductor\", \"diffuse\"")),
    };

    let sampling = match r.string("vndf_sampling")?.unwrap_or("exact") {
        "exact" => VndfSampling::Exact,
        "mixture" => {
            if matches!(micro_bsdf, MicroBsdf::Diffuse { .. }) {
                return Err(Error::new(ErrorKind::InvalidValue,
                    "vndf_sampling \"mixture\" applies to conductor flakes only"));
            }
            match ndf {
                // seeds/000 Eq. 40 for the generalized NDF.
                Ndf::Gpss(gpss) => {
                    let ratio = r.float("mixture_ratio")?.unwrap_or(0.5);
                    VndfSampling::Mixture(BeckmannUniformMixture::new(gpss, ratio)?)
                }
                // seeds/001 Appendix B for the height fields.
                _ => {
                    let ratio = r.float("mixture_ratio")?.unwrap_or(NormalUniformMixture::default_ratio(alpha_mean));
                    VndfSampling::NormalMixture(NormalUniformMixture::new(ratio)?)
                }
            }
        }
        other => return Err(invalid_choice("vndf_sampling", other, "\"exact\", \"mixture\"")),
    };

    r.finish()?;
    Ok(MacrofacetMedium { height, phase: MacrofacetPhase { ndf, micro_bsdf, sampling } })
}

/// A height-field microfacet distribution from named parameters, for a surface BSDF (a host's
/// `roughconductor`): `distribution` (`beckmann`, `ggx` or `gtr`; default `beckmann` as in
/// Mitsuba 3), `alpha` or `alpha_u`/`alpha_v`, `gamma` and `lambda` (GTR), `stretch` or
/// `transform_*`. Other names are errors.
pub fn ndf_from_params(params: &ParamSet) -> Result<Ndf> {
    let r = Reader::new(params);
    let (ndf, _) = read_ndf(&r, None, "beckmann")?;
    r.finish()?;
    Ok(ndf)
}

/// The distribution and its mean tangential roughness `sqrt(α_u α_v)`. `sigma` is `None` for a
/// surface (no kernel form, no `gpss`). Parameters are read here so that a per-query `gamma` or
/// `M` (textures) needs only another call of the constructors below, which are cheap except for
/// GTR's Gauss–Jacobi nodes (O(20²) work).
fn read_ndf(r: &Reader, sigma: Option<f64>, default: &str) -> Result<(Ndf, f64)> {
    let distribution = r.string("distribution")?.unwrap_or(default);
    let choices = if sigma.is_some() { "\"beckmann\", \"ggx\", \"gtr\", \"gpss\"" } else { "\"beckmann\", \"ggx\", \"gtr\"" };
    let supported = matches!(distribution, "beckmann" | "ggx" | "gtr") || (distribution == "gpss" && sigma.is_some());
    if !supported {
        return Err(invalid_choice("distribution", distribution, choices));
    }
    if distribution != "gtr" && (r.has("gamma") || r.has("lambda")) {
        return Err(Error::new(ErrorKind::UnknownParameter, "\"gamma\" / \"lambda\" apply to distribution \"gtr\" only"));
    }
    let alphas = match sigma {
        Some(sigma) => read_roughness(r, sigma, distribution == "gpss")?,
        None => {
            if let Some(name) = ["lengthscale", "lengthscale_x", "lengthscale_y", "lengthscale_z"].into_iter().find(|n| r.has(n)) {
                return Err(Error::new(ErrorKind::UnknownParameter,
                    format!("\"{name}\" needs \"sigma\" (a medium); a surface takes \"alpha\" or \"alpha_u\"/\"alpha_v\"")));
            }
            read_roughness(r, f64::NAN, false)?
        }
    };
    let alpha_mean = (alphas[0] * alphas[1]).sqrt();
    let transform = read_transform(r)?;
    if distribution == "gpss" {
        if transform.is_some() {
            return Err(Error::new(ErrorKind::UnknownParameter,
                "a microsurface transform (\"stretch\", \"transform_*\") applies to the height fields \"beckmann\", \"ggx\", \"gtr\" only"));
        }
        return Ok((Ndf::Gpss(Gpss::new(alphas[0], alphas[1], alphas[2])?), alpha_mean));
    }
    // GTR is shape-variant: its anisotropy is the transform diag(α/α_u, α/α_v) of the isotropic
    // GTR with α = sqrt(α_u α_v) (seeds/001 Eq. 29, area preserving); a user transform acts
    // after it (normals map by (M_user M_aniso)^{-T}).
    let (base, anisotropy) = match distribution {
        "beckmann" => (LtmdBase::Beckmann(Beckmann::new(alphas[0], alphas[1])?), None),
        "ggx" => (LtmdBase::Ggx(Ggx::new(alphas[0], alphas[1])?), None),
        _ => {
            let gamma = r.float("gamma")?.ok_or_else(|| {
                missing("distribution \"gtr\" needs \"gamma\", the tail exponent in (0, 4] (1 = Berry, 2 = GGX)".into())
            })?;
            let lambda = match r.string("lambda")?.unwrap_or("exact") {
                "exact" => GtrLambda::Exact,
                "dimov" => GtrLambda::Dimov,
                other => return Err(invalid_choice("lambda", other, "\"exact\", \"dimov\"")),
            };
            let gtr = Gtr::new(alpha_mean, gamma, lambda)?;
            let anisotropy = (alphas[0] != alphas[1])
                .then(|| glam::DMat2::from_diagonal(glam::DVec2::new(alpha_mean / alphas[0], alpha_mean / alphas[1])));
            (LtmdBase::Gtr(gtr), anisotropy)
        }
    };
    let matrix = match (transform, anisotropy) {
        (None, None) => {
            let ndf = match base {
                LtmdBase::Beckmann(b) => Ndf::Beckmann(b),
                LtmdBase::Ggx(g) => Ndf::Ggx(g),
                LtmdBase::Gtr(g) => Ndf::Gtr(g),
            };
            return Ok((ndf, alpha_mean));
        }
        (Some(m), None) | (None, Some(m)) => m,
        (Some(user), Some(aniso)) => user * aniso,
    };
    Ok((Ndf::Ltmd(Ltmd::new(base, matrix)?), alpha_mean))
}

/// The microsurface transform: `stretch` (seeds/001 Eq. 31) or the four `transform_*` entries of `M`
/// (seeds/001 Eq. 9), or none.
fn read_transform(r: &Reader) -> Result<Option<glam::DMat2>> {
    const NAMES: [&str; 4] = ["transform_xx", "transform_xy", "transform_yx", "transform_yy"];
    let stretch = r.float("stretch")?;
    let entries = [r.float(NAMES[0])?, r.float(NAMES[1])?, r.float(NAMES[2])?, r.float(NAMES[3])?];
    let given = entries.iter().filter(|e| e.is_some()).count();
    match (stretch, given) {
        (None, 0) => Ok(None),
        (Some(s), 0) => Ltmd::stretch_matrix(s).map(Some),
        (None, 4) => {
            let [xx, xy, yx, yy] = entries.map(|e| e.unwrap_or(0.0));
            Ok(Some(glam::DMat2::from_cols(glam::DVec2::new(xx, yx), glam::DVec2::new(xy, yy))))
        }
        (None, _) => {
            let absent: Vec<&str> = NAMES.iter().zip(&entries).filter(|(_, e)| e.is_none()).map(|(n, _)| *n).collect();
            Err(missing(format!("a microsurface transform needs all four of \"transform_xx\", \"transform_xy\", \"transform_yx\", \"transform_yy\"; missing {absent:?}")))
        }
        (Some(_), _) => Err(missing("give either \"stretch\" or the \"transform_*\" matrix, not both".into())),
    }
}

/// `sigma` from `sigma` or `variance` (exactly one), within [`crate::limits::SIGMA_RANGE`].
pub fn read_sigma(r: &Reader) -> Result<f64> {
    match (r.float("sigma")?, r.float("variance")?) {
        (Some(s), None) => check_sigma("parameter \"sigma\"", check_positive("sigma", s, false)?),
        (None, Some(v)) => check_sigma("sigma = sqrt(\"variance\")", check_positive("variance", v, false)?.sqrt()),
        (Some(_), Some(_)) => Err(missing("give either \"sigma\" or \"variance\", not both".into())),
        (None, None) => Err(missing("\"sigma\" (or \"variance\") is required".into())),
    }
}

/// `[alpha_x, alpha_y, alpha_z]` from either the roughness or the kernel form.
pub fn read_roughness(r: &Reader, sigma: f64, with_z: bool) -> Result<[f64; 3]> {
    let alpha_names = ["alpha", "alpha_u", "alpha_v", "alpha_z"];
    let kernel_names = ["lengthscale", "lengthscale_x", "lengthscale_y", "lengthscale_z"];
    let uses_alpha = alpha_names.iter().any(|n| r.has(n));
    let uses_kernel = kernel_names.iter().any(|n| r.has(n));
    if uses_alpha && uses_kernel {
        return Err(missing("give the roughness either as alpha* or as lengthscale*, not both".into()));
    }
    if !with_z && (r.has("alpha_z") || r.has("lengthscale_z")) {
        return Err(Error::new(ErrorKind::UnknownParameter,
            "\"alpha_z\" / \"lengthscale_z\" apply to distribution \"gpss\" only"));
    }
    let names = if uses_kernel { kernel_names } else { alpha_names };
    // Kernel form: alpha_i = √2 σ / l_i (seeds/000 Eq. 4); roughness form: as given.
    // Checked here so that the message names the parameter as given (alpha_z may be 0).
    let to_alpha = |name: &str, v: f64| -> Result<f64> {
        if uses_kernel {
            let alpha = alpha_from_kernel(sigma, check_positive(name, v, false)?);
            let subject = format!("the roughness sqrt(2) sigma / \"{name}\" (with \"{name}\" = {v:e})");
            let check = if name == "lengthscale_z" { check_alpha_z } else { check_roughness };
            check(&subject, alpha)
        } else {
            let subject = format!("parameter \"{name}\"");
            // "alpha" also sets alpha_z (an isotropic kernel): within both ranges then.
            if name == "alpha_z" { check_alpha_z(&subject, v) } else { check_roughness(&subject, v) }
        }
    };
    let read = |i: usize| -> Result<Option<f64>> { r.float(names[i])?.map(|v| to_alpha(names[i], v)).transpose() };
    let (iso, x, y, z) = (read(0)?, read(1)?, read(2)?, read(3)?);
    let pair = match (iso, x, y) {
        (Some(a), None, None) => [a, a],
        (None, Some(ax), Some(ay)) => [ax, ay],
        (None, None, None) => {
            return Err(missing(format!("the roughness is missing: give \"{}\" or \"{}\" and \"{}\"", names[0], names[1], names[2])))
        }
        _ => {
            return Err(missing(format!("give either \"{}\" or both \"{}\" and \"{}\"", names[0], names[1], names[2])))
        }
    };
    let alpha_z = match (with_z, iso, z) {
        (false, _, _) => 0.0,
        (true, _, Some(az)) => az,
        (true, Some(a), None) => a, // isotropic kernel: l_x = l_y = l_z
        (true, None, None) => {
            return Err(missing(format!("distribution \"gpss\" with \"{}\"/\"{}\" also needs \"{}\" (0 for a height field)", names[1], names[2], names[3])))
        }
    };
    Ok([pair[0], pair[1], alpha_z])
}

pub fn read_conductor(r: &Reader) -> Result<MicroBsdf> {
    let specular_reflectance = r.unit_rgb("specular_reflectance", 1.0)?;
    let material = r.string("material")?;
    let (eta, k) = (r.rgb("eta")?, r.rgb("k")?);
    match (material, eta, k) {
        (Some(_), Some(_), _) | (Some(_), _, Some(_)) => {
            Err(missing("give either \"material\" or \"eta\" and \"k\", not both".into()))
        }
        (Some("none") | None, None, None) => Ok(MicroBsdf::Mirror { specular_reflectance }),
        (Some(name), None, None) => {
            let preset = conductor_preset(name).ok_or_else(|| {
                invalid_choice("material", name, "\"none\", \"Ag\", \"Al\", \"Au\", \"Cr\", \"Cu\"")
            })?;
            Ok(MicroBsdf::Conductor { eta: preset.eta, k: preset.k, specular_reflectance })
        }
        (None, Some(eta), Some(k)) => {
            for c in 0..3 {
                check_conductor_index("eta", c, eta[c])?;
                check_conductor_index("k", c, k[c])?;
            }
            Ok(MicroBsdf::Conductor { eta, k, specular_reflectance })
        }
        (None, _, _) => Err(missing("a conductor index needs both \"eta\" and \"k\"".into())),
    }
}
