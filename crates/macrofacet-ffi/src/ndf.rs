//! `mf_ndf`: the library's height-field microfacet distributions (Beckmann, GGX, GTR, and their
//! tangent-plane transforms, seeds/001) for a host's surface BSDF, so that a `roughconductor`
//! and a thin macrofacet shell use the same `D`, Λ and visible-normal sampler.
//!
//! Same conventions as the phase calls: an `mf_frame` (normal, tangent carrying `alpha_u` and
//! the transform's `x` axis) and world-space unit directions; `wi` points away from the surface.

use super::medium::{frame, local_direction, mf_frame, mf_vec3, uniform};
use super::{arg, boundary, free_handle, into_handle, mf_params, mf_status, out};
use macrofacet::ndf::{MicrofacetDistribution, Ndf};
use macrofacet::params::ndf_from_params;
use glam::DVec3;

/// Uniform numbers consumed by [`mf_ndf_sample_visible`].
pub const MF_NDF_SAMPLE_DIMENSIONS: usize = 3;

/// An immutable microfacet distribution. Safe to share between threads.
pub struct mf_ndf {
    pub(crate) inner: Ndf,
}

/// A sampled visible normal. `valid` is false when no microfacet is visible from `wi` (then the
/// other fields are zero).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct mf_ndf_sample {
    /// The microfacet normal, world space.
    pub m: mf_vec3,
    /// Its density per solid angle, `D_wi(m) = <wi, m> D(m) / ((1 + Λ(wi)) cos θ_wi)` with the
    /// exact projected area of `D` (seeds/001 Eq. 27).
    pub pdf: f64,
    pub valid: bool,
}

/// Creates a distribution from named parameters: `distribution` (`beckmann`, `ggx` or `gtr`;
/// default `beckmann`), `alpha` or `alpha_u`/`alpha_v`, `gamma` and `lambda` for `gtr`,
/// `stretch` or `transform_xx`/`_xy`/`_yx`/`_yy`. Other names are errors. On failure nothing is
/// written and [`super::mf_last_error_message`] names the parameter.
///
/// # Safety
/// `params` must be a live handle (or NULL); `out_ndf` NULL or valid for writes.
#[no_mangle]
pub unsafe extern "C" fn mf_ndf_new(params: *const mf_params, out_ndf: *mut *mut mf_ndf) -> mf_status {
    boundary(|| {
        let p = arg(params, "params")?;
        let slot = out(out_ndf, "out_ndf")?;
        let inner = ndf_from_params(&p.inner)?;
        *slot = into_handle(mf_ndf { inner });
        Ok(())
    })
}

/// Releases a distribution; NULL is a no-op.
///
/// # Safety
/// `ndf` must be NULL or a pointer from [`mf_ndf_new`] not yet freed.
#[no_mangle]
pub unsafe extern "C" fn mf_ndf_free(ndf: *mut mf_ndf) {
    free_handle(ndf);
}

/// `D(m)` per steradian (normalised by `∫ D(m)(m·n) dm = 1`); 0 below the horizon.
///
/// # Safety
/// Pointers must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mf_ndf_eval(ndf: *const mf_ndf, frame_: *const mf_frame, m: mf_vec3, out_d: *mut f64) -> mf_status {
    boundary(|| {
        let n = arg(ndf, "ndf")?;
        let fr = frame(arg(frame_, "frame")?)?;
        let m = local_direction(&fr, "m", m)?;
        *out(out_d, "out_d")? = n.inner.d(m);
        Ok(())
    })
}

/// Smith's `Λ(w)` extended to the whole sphere (`Λ(−w) = −1 − Λ(w)`); `+inf` on the horizon
/// seen from above, `-inf` from below. Height-correlated masking-shadowing is
/// `1 / (1 + Λ(wi) + Λ(wo))`, `G1(w) = 1 / (1 + Λ(w))`.
///
/// # Safety
/// Pointers must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mf_ndf_lambda(ndf: *const mf_ndf, frame_: *const mf_frame, w: mf_vec3, out_lambda: *mut f64) -> mf_status {
    boundary(|| {
        let n = arg(ndf, "ndf")?;
        let fr = frame(arg(frame_, "frame")?)?;
        let w = local_direction(&fr, "w", w)?;
        // The horizon: the projected area is finite, cos θ is ±0.
        let lambda = if w.z == 0.0 { f64::INFINITY } else { n.inner.lambda(w) };
        *out(out_lambda, "out_lambda")? = lambda;
        Ok(())
    })
}

/// Samples a visible normal from `wi` with [`MF_NDF_SAMPLE_DIMENSIONS`] uniform numbers in
/// `[0, 1)` read from `u` (exact sampling of `<wi, m> D(m)` for every distribution).
///
/// # Safety
/// Pointers must be NULL or valid; `u` must hold `MF_NDF_SAMPLE_DIMENSIONS` doubles.
#[no_mangle]
pub unsafe extern "C" fn mf_ndf_sample_visible(
    ndf: *const mf_ndf,
    frame_: *const mf_frame,
    wi: mf_vec3,
    u: *const f64,
    out_sample: *mut mf_ndf_sample,
) -> mf_status {
    boundary(|| {
        let n = arg(ndf, "ndf")?;
        let fr = frame(arg(frame_, "frame")?)?;
        let wi = local_direction(&fr, "wi", wi)?;
        let first = arg(u, "u")?;
        // SAFETY: the caller promises MF_NDF_SAMPLE_DIMENSIONS readable doubles at `u`.
        let u: [f64; MF_NDF_SAMPLE_DIMENSIONS] =
            unsafe { std::slice::from_raw_parts(first, MF_NDF_SAMPLE_DIMENSIONS) }.try_into().expect("length");
        for (i, x) in u.iter().enumerate() {
            uniform(format_args!("u[{i}]"), *x)?;
        }
        let slot = out(out_sample, "out_sample")?;
        // The pdf is that of the world-space `m` the host gets back, taken to the local frame as
        // `mf_ndf_pdf_visible` takes it, so the two agree bit for bit (as `mf_phase_sample` and
        // `mf_phase_pdf` do). A sample whose density there is below the smallest normal f64 (a
        // normal on the horizon of a 1e-4 lobe, found by fuzzing) is not returned: its pdf has
        // lost its precision and such samples have a total probability below 4π · 2.2e-308.
        let sample = n.inner.sample_visible(wi, u).and_then(|m| {
            let m_world: mf_vec3 = fr.to_world(m).into();
            let pdf = n.inner.pdf_visible(wi, local_direction(&fr, "m", m_world).ok()?);
            (pdf >= f64::MIN_POSITIVE && pdf.is_finite()).then_some(mf_ndf_sample { m: m_world, pdf, valid: true })
        });
        *slot = sample.unwrap_or(mf_ndf_sample { m: DVec3::ZERO.into(), pdf: 0.0, valid: false });
        Ok(())
    })
}

/// The density of [`mf_ndf_sample_visible`] at `m` (per solid angle of `m`).
///
/// # Safety
/// Pointers must be NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mf_ndf_pdf_visible(
    ndf: *const mf_ndf,
    frame_: *const mf_frame,
    wi: mf_vec3,
    m: mf_vec3,
    out_pdf: *mut f64,
) -> mf_status {
    boundary(|| {
        let n = arg(ndf, "ndf")?;
        let fr = frame(arg(frame_, "frame")?)?;
        let (wi, m) = (local_direction(&fr, "wi", wi)?, local_direction(&fr, "m", m)?);
        *out(out_pdf, "out_pdf")? = n.inner.pdf_visible(wi, m);
        Ok(())
    })
}
