//! Parameter sets, media and gpis handles from fuzz bytes, built through the ABI
//! (`mf_params_*`, `mf_medium_new`, `mf_gpis_new`) with every status checked.

use crate::check;
use crate::input::Bytes;
use macrofacet_ffi::*;
use std::ffi::CString;

/// A parameter value as `mf_params_set_*` takes it.
#[derive(Clone)]
pub enum Value {
    Float(f64),
    Rgb([f64; 3]),
    String(Vec<u8>),
}

/// A named parameter (the name may be any bytes without NUL).
#[derive(Clone)]
pub struct Param {
    pub name: Vec<u8>,
    pub value: Value,
}

impl std::fmt::Debug for Param {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let name = String::from_utf8_lossy(&self.name);
        match &self.value {
            Value::String(s) => write!(f, "{name:?} = {:?}", String::from_utf8_lossy(s)),
            Value::Float(x) => write!(f, "{name:?} = {x:e}"),
            Value::Rgb(c) => write!(f, "{name:?} = [{:e}, {:e}, {:e}]", c[0], c[1], c[2]),
        }
    }
}

fn float(name: &str, x: f64) -> Param {
    Param { name: name.into(), value: Value::Float(x) }
}

fn string(name: &str, s: &str) -> Param {
    Param { name: name.into(), value: Value::String(s.into()) }
}

fn rgb(name: &str, c: [f64; 3]) -> Param {
    Param { name: name.into(), value: Value::Rgb(c) }
}

/// Every name a medium or gpis takes (README, "Medium parameters"), for the params target.
pub const NAMES: [&str; 22] = [
    "sigma", "variance", "shell_extent", "distribution", "alpha", "alpha_u", "alpha_v", "alpha_z", "lengthscale",
    "lengthscale_x", "lengthscale_y", "lengthscale_z", "micro_bsdf", "material", "eta", "k", "specular_reflectance",
    "reflectance", "vndf_sampling", "mixture_ratio", "memory", "step_correlation",
];

/// Every string value a parameter takes.
pub const STRING_VALUES: [&str; 16] = [
    "beckmann", "ggx", "gpss", "conductor", "diffuse", "none", "Ag", "Al", "Au", "Cr", "Cu", "exact", "mixture", "renewal",
    "renewal_plus", "",
];

/// A random unit-interval RGB, sometimes outside it.
fn color(b: &mut Bytes) -> [f64; 3] {
    if b.u8() % 8 == 0 {
        [b.float(), b.float(), b.float()]
    } else {
        [b.unit(), b.unit(), b.unit()]
    }
}

/// The roughness of a medium or gpis of height deviation `sigma`: one of the parameter forms,
/// values mostly in the domain (lengthscales mostly `√2 σ / α` for such an `α`).
fn roughness(b: &mut Bytes, params: &mut Vec<Param>, sigma: f64, with_z: bool, largest_log10: f64) {
    let alpha = |b: &mut Bytes| b.positive(-6.0, largest_log10);
    let alpha_z = |b: &mut Bytes| if b.u8() % 3 == 0 { 0.0 } else { b.positive(-8.0, largest_log10) };
    let length = |b: &mut Bytes| if b.u8() % 8 == 0 { b.positive(-4.0, 4.0) } else { std::f64::consts::SQRT_2 * sigma / alpha(b) };
    match b.u8() % 4 {
        0 => params.push(float("alpha", alpha(b))),
        1 => {
            params.push(float("alpha_u", alpha(b)));
            params.push(float("alpha_v", alpha(b)));
            if with_z {
                params.push(float("alpha_z", alpha_z(b)));
            }
        }
        2 => params.push(float("lengthscale", length(b))),
        _ => {
            params.push(float("lengthscale_x", length(b)));
            params.push(float("lengthscale_y", length(b)));
            if with_z {
                params.push(float("lengthscale_z", length(b)));
            }
        }
    }
}

/// The flakes' reflectance: a conductor preset, `eta`/`k`, a mirror.
fn conductor(b: &mut Bytes, params: &mut Vec<Param>) {
    match b.u8() % 4 {
        0 => params.push(string("material", b.choose(&["none", "Ag", "Al", "Au", "Cr", "Cu"]))),
        1 => {
            params.push(rgb("eta", [b.positive(-2.0, 1.0), b.positive(-2.0, 1.0), b.positive(-2.0, 1.0)]));
            params.push(rgb("k", [b.positive(-3.0, 1.5), b.positive(-3.0, 1.5), b.positive(-3.0, 1.5)]));
        }
        _ => {}
    }
    if b.bool() {
        params.push(rgb("specular_reflectance", color(b)));
    }
}

/// A medium's parameters: mostly valid (in the domain of README, "Medium parameters"), so that
/// the query targets get a medium; the odd value outside it exercises the refusals.
pub fn medium_params(b: &mut Bytes) -> Vec<Param> {
    let mut params = Vec::new();
    let sigma = if b.u8() % 8 == 0 {
        let variance = b.positive(-100.0, 100.0);
        params.push(float("variance", variance));
        variance.sqrt()
    } else {
        let sigma = b.positive(-50.0, 50.0);
        params.push(float("sigma", sigma));
        sigma
    };
    if b.bool() {
        params.push(float("shell_extent", b.positive(-3.0, 1.6)));
    }
    let distribution = b.choose(&["gpss", "gpss", "beckmann", "ggx"]);
    params.push(string("distribution", distribution));
    roughness(b, &mut params, sigma, distribution == "gpss", 6.0);
    if b.u8() % 4 == 0 {
        params.push(string("micro_bsdf", "diffuse"));
        params.push(rgb("reflectance", color(b)));
    } else {
        conductor(b, &mut params);
        if distribution == "gpss" && b.u8() % 3 == 0 {
            params.push(string("vndf_sampling", "mixture"));
            params.push(float("mixture_ratio", b.positive(-6.0, 0.0) * (1.0 - 1e-12)));
        }
    }
    params
}

/// A gpis's parameters: mostly valid, with roughness, band and step kept where a trace costs
/// tens of microseconds (one input in 16 may cost milliseconds: up to α = 10, ρ = 0.999), so that
/// the target runs 1e7 inputs in hours (the march bound refuses what costs more).
pub fn gpis_params(b: &mut Bytes) -> Vec<Param> {
    let sigma = b.positive(-50.0, 50.0);
    let mut params = vec![float("sigma", sigma)];
    let height_field = b.u8() % 3 == 0;
    params.push(string("distribution", if height_field { "beckmann" } else { "gpss" }));
    let expensive = b.u8() % 16 == 0;
    roughness(b, &mut params, sigma, !height_field, if expensive { 1.0 } else { 0.0 });
    params.push(string("memory", b.choose(&["renewal", "renewal_plus"])));
    if b.u8() % 4 == 0 {
        let rho = if expensive { b.choose(&[0.99, 0.999]) } else { b.choose(&[0.5, 0.9, 0.95]) };
        params.push(float("step_correlation", rho));
    }
    if b.u8() % 4 == 0 {
        params.push(float("shell_extent", if expensive { b.positive(0.4, 1.6) } else { b.positive(0.4, 0.9) }));
    }
    conductor(b, &mut params);
    params
}

/// Any parameter set: known and unknown names, any type and value (the params target).
pub fn arbitrary_params(b: &mut Bytes) -> Vec<Param> {
    let count = b.below(12);
    (0..count)
        .map(|_| {
            let name = if b.u8() % 8 == 0 { b.string(24) } else { b.choose(&NAMES).into() };
            let value = match b.u8() % 3 {
                0 => Value::Float(if b.bool() { b.float() } else { b.positive(-8.0, 8.0) }),
                1 => Value::Rgb([b.float(), b.positive(-3.0, 1.0), b.unit()]),
                _ => Value::String(if b.u8() % 8 == 0 { b.string(24) } else { b.choose(&STRING_VALUES).into() }),
            };
            Param { name, value }
        })
        .collect()
}

/// The `sigma` a parameter set gives (from `sigma` or `variance`), as the library reads it.
pub fn sigma(params: &[Param]) -> Option<f64> {
    params.iter().rev().find_map(|p| match (&p.name[..], &p.value) {
        (b"sigma", Value::Float(x)) => Some(*x),
        (b"variance", Value::Float(x)) => Some(x.sqrt()),
        _ => None,
    })
}

/// An `mf_params` handle, freed on drop.
pub struct Params(pub *mut mf_params);

impl Drop for Params {
    fn drop(&mut self) {
        // SAFETY: from mf_params_new, freed once.
        unsafe { mf_params_free(self.0) };
    }
}

/// Fills an `mf_params` through the setters. A setter fails only for a non-finite float or rgb
/// and a name or string value that is not UTF-8 (then the parameter is absent). With the
/// environment variable `MF_FUZZ_DEBUG` set, prints the parameters (to read a crash artifact).
pub fn params_handle(params: &[Param]) -> Params {
    if std::env::var_os("MF_FUZZ_DEBUG").is_some() {
        eprintln!("parameters: {params:?}");
    }
    let handle = Params(check::call(|out| unsafe { mf_params_new(out) }).expect("mf_params_new"));
    for p in params {
        let name = CString::new(p.name.clone()).expect("no interior NUL");
        // SAFETY: live handle, NUL-terminated strings, three readable doubles.
        let status = unsafe {
            match &p.value {
                Value::Float(x) => mf_params_set_float(handle.0, name.as_ptr(), *x),
                Value::Rgb(c) => mf_params_set_rgb(handle.0, name.as_ptr(), c.as_ptr()),
                Value::String(s) => mf_params_set_string(handle.0, name.as_ptr(), CString::new(s.clone()).expect("no NUL").as_ptr()),
            }
        };
        let expected_failure = std::str::from_utf8(&p.name).is_err()
            || match &p.value {
                Value::Float(x) => !x.is_finite(),
                Value::Rgb(c) => !c.iter().all(|x| x.is_finite()),
                Value::String(s) => std::str::from_utf8(s).is_err(),
            };
        assert_eq!(check::status(status).is_err(), expected_failure, "setting {p:?}: {status:?}");
    }
    handle
}

/// An `mf_medium`, freed on drop.
pub struct Medium(pub *mut mf_medium);

impl Drop for Medium {
    fn drop(&mut self) {
        // SAFETY: from mf_medium_new, freed once.
        unsafe { mf_medium_free(self.0) };
    }
}

/// An `mf_gpis`, freed on drop.
pub struct Gpis(pub *mut mf_gpis);

impl Drop for Gpis {
    fn drop(&mut self) {
        // SAFETY: from mf_gpis_new, freed once.
        unsafe { mf_gpis_free(self.0) };
    }
}

/// `mf_medium_new` from `params`; `None` when refused (the refusal itself is checked).
pub fn medium(params: &[Param]) -> Option<Medium> {
    let handle = params_handle(params);
    check::call(|out| unsafe { mf_medium_new(handle.0, out) }).ok().map(Medium)
}

/// `mf_gpis_new` from `params`; `None` when refused (the refusal itself is checked).
pub fn gpis(params: &[Param]) -> Option<Gpis> {
    let handle = params_handle(params);
    check::call(|out| unsafe { mf_gpis_new(handle.0, out) }).ok().map(Gpis)
}

/// Every name `mf_ndf_new` takes (header, `mf_ndf_new`).
pub const NDF_NAMES: [&str; 11] = ["distribution", "alpha", "alpha_u", "alpha_v", "gamma", "lambda", "stretch", "transform_xx", "transform_xy", "transform_yx", "transform_yy"];

/// A distribution's parameters (`mf_ndf_new`): mostly valid — Beckmann, GGX or GTR (any `gamma`
/// in (0, 4], either Λ), isotropic or anisotropic, sometimes stretched or transformed — with
/// the odd value outside the domain, or any names and values.
pub fn ndf_params(b: &mut Bytes) -> Vec<Param> {
    if b.u8() % 8 == 0 {
        let mut params = arbitrary_params(b);
        for _ in 0..b.below(3) {
            let value = if b.bool() { Value::Float(b.float()) } else { Value::String(b.choose(&STRING_VALUES).into()) };
            params.push(Param { name: b.choose(&NDF_NAMES).into(), value });
        }
        return params;
    }
    let mut params = Vec::new();
    let distribution = b.choose(&["beckmann", "ggx", "gtr", "gtr"]);
    if distribution != "beckmann" || b.bool() {
        params.push(string("distribution", distribution));
    }
    if distribution == "gtr" {
        let gamma = match b.u8() % 8 {
            0 => b.choose(&[1.0, 2.0, 3.0, 4.0, 1.0 + 1e-9, 2.0 - 1e-12, 4.0 * (1.0 + 1e-12), 1e-3]),
            1 => b.float(),
            _ => 4.0 * b.unit().max(1e-3),
        };
        params.push(float("gamma", gamma));
        if b.bool() {
            params.push(string("lambda", b.choose(&["exact", "dimov"])));
        }
    }
    let alpha = |b: &mut Bytes| b.positive(-4.0, 3.0);
    match b.u8() % 8 {
        0 => {}
        1..=4 => params.push(float("alpha", alpha(b))),
        _ => {
            params.push(float("alpha_u", alpha(b)));
            params.push(float("alpha_v", alpha(b)));
        }
    }
    match b.u8() % 8 {
        0 => params.push(float("stretch", if b.u8() % 4 == 0 { b.float() } else { 2.0 * b.unit() - 1.0 })),
        1 => {
            for name in ["transform_xx", "transform_xy", "transform_yx", "transform_yy"] {
                params.push(float(name, if b.u8() % 8 == 0 { b.float() } else { b.signed_distance(0.5) }));
            }
        }
        _ => {}
    }
    params
}

/// An `mf_ndf`, freed on drop.
pub struct Ndf(pub *mut mf_ndf);

impl Drop for Ndf {
    fn drop(&mut self) {
        // SAFETY: from mf_ndf_new, freed once.
        unsafe { mf_ndf_free(self.0) };
    }
}

/// `mf_ndf_new` from `params`; `None` when refused (the refusal itself is checked).
pub fn ndf(params: &[Param]) -> Option<Ndf> {
    let handle = params_handle(params);
    check::call(|out| unsafe { mf_ndf_new(handle.0, out) }).ok().map(Ndf)
}

/// The largest roughness a parameter set gives (`alpha*`, or `√2 σ / lengthscale*`, seeds/000
/// Eq. 4), NaN when it gives none.
pub fn largest_alpha(params: &[Param]) -> f64 {
    let sigma = sigma(params).unwrap_or(f64::NAN);
    params
        .iter()
        .filter_map(|p| match (std::str::from_utf8(&p.name), &p.value) {
            (Ok(name), Value::Float(x)) if name.starts_with("alpha") => Some(*x),
            (Ok(name), Value::Float(l)) if name.starts_with("lengthscale") => Some(std::f64::consts::SQRT_2 * sigma / l),
            _ => None,
        })
        .fold(f64::NAN, f64::max)
}
