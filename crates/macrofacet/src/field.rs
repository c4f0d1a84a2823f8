//! Spatially varying media: the parameters of a non-stationary GPSS (seeds/004 Sec. 6.1) given per
//! point by a *field* that the host evaluates (grids, textures, procedures); the library stays
//! pure. Locally the kernel `σ(x)σ(y) … k(√Q(x, y))` of seeds/004 Eqs. 25–26 is a stationary one
//! with variance `σ(x)²` and lengthscale matrix `Σ(x)`, so at a point the medium is the stationary
//! macrofacet medium of those local parameters: `σ_t = ρ(f; σ(x)) σ(d; α(x))` (
//! seeds/000 Eqs. 13–14) with the roughness `α = √2 σ/l` (seeds/000 Eq. 4) or, for a full anisotropy, the roughness
//! matrix `Q = 2σ² Rᵀ Σ⁻¹ R` in the local frame `R = (t, b, n)` ([`crate::ndf::GpssMatrix`]).
//!
//! For majorants a field bounds its parameters along a segment ([`ParamBounds`]); the tracker
//! turns those into a bound of `σ_t` ([`ParamBounds::density_factor`]) and counts every tentative
//! collision where the bound failed.

use crate::error::{check_positive, Error, ErrorKind, Result};
use crate::limits::{ROUGHNESS_RANGE, SIGMA_RANGE};
use crate::frame::Frame;
use crate::height::HeightProfile;
use crate::ndf::{Beckmann, BeckmannUniformMixture, Ggx, Gpss, GpssMatrix, Ltmd, LtmdBase, Ndf};
use crate::surface::SurfacePoint;
use crate::{MacrofacetMedium, Rgb, VndfSampling};
use glam::{DMat2, DMat3, DVec2, DVec3};

/// What varies at one point; `None` keeps the medium's own value.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LocalParams {
    /// The heights' standard deviation `σ` (scene units).
    pub sigma: Option<f64>,
    /// Roughness along the local tangent, bitangent and normal (`alpha_u`, `alpha_v`,
    /// `alpha_z`); Beckmann and GGX read the first two, `alpha_z = 0` is a height field.
    pub alpha: Option<DVec3>,
    /// The kernel's local anisotropy `Σ` of seeds/004 Eq. 25 in world space (symmetric positive
    /// definite, lengthscales² on its axes): the roughness matrix is `Q = 2σ² Rᵀ Σ⁻¹ R`. Only for
    /// `gpss` media; takes precedence over `alpha`.
    pub anisotropy: Option<DMat3>,
    /// Multiplies the flakes' reflectance (the result must stay within `[0, 1]`).
    pub reflectance_scale: Option<Rgb>,
}

/// Bounds of a field along a segment: `σ ∈ [sigma[0], sigma[1]]`, and every roughness the NDF
/// sees — each `alpha` component, or `√(λ(Q))` over the eigenvalues of `Q` — within
/// `[alpha[0], alpha[1]]`. `None`: the medium's constant.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ParamBounds {
    pub sigma: Option<[f64; 2]>,
    pub alpha: Option<[f64; 2]>,
}

/// A source of local parameters. Implementations must be deterministic.
pub trait MediumField {
    /// The parameters at `p`, where the mean surface is `point`.
    fn at(&self, p: DVec3, point: &SurfacePoint) -> Result<LocalParams>;

    /// Bounds along `p + s d`, `s ∈ [0, length]`.
    fn bounds(&self, p: DVec3, d: DVec3, length: f64) -> Result<ParamBounds>;

    /// The largest `σ` anywhere (the shell's top is at `k σ_max`); `None`: the medium's `σ`.
    fn sigma_max(&self) -> Option<f64>;

    /// False for a field that never varies (the tracker then skips every field query).
    fn varies(&self) -> bool {
        true
    }
}

/// The stationary medium: nothing varies.
#[derive(Clone, Copy, Debug, Default)]
pub struct Constant;

impl MediumField for Constant {
    fn at(&self, _: DVec3, _: &SurfacePoint) -> Result<LocalParams> {
        Ok(LocalParams::default())
    }
    fn bounds(&self, _: DVec3, _: DVec3, _: f64) -> Result<ParamBounds> {
        Ok(ParamBounds::default())
    }
    fn sigma_max(&self) -> Option<f64> {
        None
    }
    fn varies(&self) -> bool {
        false
    }
}

impl ParamBounds {
    /// Checks what a field returned (`what` names it in the message) and clips it to the
    /// parameters' domain ([`SIGMA_RANGE`], [`ROUGHNESS_RANGE`]): a value beyond is refused where
    /// the field is evaluated, so the majorant need not cover it. Bounds that leave no value of
    /// the domain are refused at once (found by fuzzing: a field declaring α in [5e264, 1e265]
    /// went through 131,072 tentative collisions, as ratio tracking's thinning never asked it
    /// for a value, before the call failed).
    pub fn validated(self, what: &str) -> Result<ParamBounds> {
        let mut clipped = self;
        for (name, range, zero_ok, domain, out) in [("sigma", self.sigma, false, SIGMA_RANGE, &mut clipped.sigma), ("alpha", self.alpha, true, ROUGHNESS_RANGE, &mut clipped.alpha)] {
            let Some([lo, hi]) = range else { continue };
            let ok = lo.is_finite() && hi.is_finite() && lo <= hi && if zero_ok { lo >= 0.0 } else { lo > 0.0 };
            if !ok {
                return Err(Error::new(ErrorKind::InvalidArgument, format!("{what}: {name} bounds must be finite and ordered with {name} {} 0, got [{lo}, {hi}]", if zero_ok { ">=" } else { ">" })));
            }
            if hi < domain.0 || lo > domain.1 {
                return Err(Error::new(ErrorKind::InvalidArgument, format!("{what}: {name} bounds [{lo:e}, {hi:e}] leave no value of the accepted range [{:e}, {:e}]", domain.0, domain.1)));
            }
            // α's lower bound may be 0 (α_z of a height field): only its upper one is clipped.
            *out = Some([if zero_ok { lo } else { lo.max(domain.0) }, hi.min(domain.1)]);
        }
        Ok(clipped)
    }

    /// `M` with `ρ(f; σ) <= M ρ(f; σ_hi)` for every `f` and every `σ ∈ [σ_lo, σ_hi]`:
    /// `M = (σ_hi/σ_lo)²`. Below the mean surface `ρ` decreases with `σ` and the hazard `h` of the
    /// normal law has `h(λt) <= λ h(t)` (`h(t) − t` decreases, `h(t) >= t`), which gives
    /// `ρ(f; σ_lo) <= (σ_hi/σ_lo)² ρ(f; σ_hi)`; above it `ρ(f; ·)` rises then falls, and its maximum
    /// exceeds `ρ(f; σ_hi)` at most by `σ_hi/σ_lo`. The top face `k σ` lies below `k σ_hi`.
    pub fn density_factor(&self) -> f64 {
        match self.sigma {
            Some([lo, hi]) if hi > lo => (hi / lo) * (hi / lo),
            _ => 1.0,
        }
    }
}

impl LocalParams {
    /// Checks the values a field returned (`what` names it in the message).
    pub fn validate(&self, what: &str) -> Result<()> {
        let bad = |m: String| Err(Error::new(ErrorKind::InvalidArgument, format!("{what}: {m}")));
        if let Some(s) = self.sigma {
            check_positive("sigma", s, false).map_err(|e| Error::new(e.kind, format!("{what}: {}", e.message)))?;
        }
        if let Some(a) = self.alpha {
            if !(a.is_finite() && a.x > 0.0 && a.y > 0.0 && a.z >= 0.0) {
                return bad(format!("alpha must be finite with alpha_u, alpha_v > 0 and alpha_z >= 0, got {a}"));
            }
        }
        if let Some(m) = self.anisotropy {
            if !m.is_finite() {
                return bad(format!("anisotropy must be finite, got {m}"));
            }
        }
        if let Some(r) = self.reflectance_scale {
            if !r.iter().all(|c| c.is_finite() && *c >= 0.0) {
                return bad(format!("reflectance_scale must be finite and >= 0, got {r:?}"));
            }
        }
        Ok(())
    }
}

impl MacrofacetMedium {
    /// The stationary medium of the local parameters at a point whose frame is `frame`
    /// (normal, tangent): what `σ_t` and the phase function use there.
    pub fn localized(&self, local: &LocalParams, frame: &Frame) -> Result<MacrofacetMedium> {
        let mut m = *self;
        if let Some(sigma) = local.sigma {
            m.height = HeightProfile::new(sigma, self.height.shell_extent)?;
        }
        if let Some(sigma_matrix) = local.anisotropy {
            if !matches!(self.phase.ndf, Ndf::Gpss(_) | Ndf::GpssMatrix(_)) {
                return Err(Error::new(ErrorKind::InvalidArgument, "anisotropy applies to gpss media (the generalized macrofacet), not to height-field distributions"));
            }
            let inverse = sigma_matrix.inverse();
            let r = DMat3::from_cols(frame.s, frame.t, frame.n);
            let q = r.transpose() * inverse * r * (2.0 * m.height.sigma * m.height.sigma);
            m.phase.ndf = Ndf::GpssMatrix(GpssMatrix::new(q, "anisotropy")?);
        } else if let Some(a) = local.alpha {
            m.phase.ndf = match self.phase.ndf {
                Ndf::Beckmann(_) => Ndf::Beckmann(Beckmann::new(a.x, a.y)?),
                Ndf::Ggx(_) => Ndf::Ggx(Ggx::new(a.x, a.y)?),
                Ndf::Gpss(_) | Ndf::GpssMatrix(_) => Ndf::Gpss(Gpss::new(a.x, a.y, a.z)?),
                // GTR depends on the slopes over α: roughness (a_u, a_v) is the stretch
                // diag(a_u, a_v)/α of the medium's GTR (seeds/001 Eqs. 22, 29).
                Ndf::Gtr(g) => Ndf::Ltmd(Ltmd::new(LtmdBase::Gtr(g), DMat2::from_diagonal(DVec2::new(a.x, a.y) / g.alpha))?),
                Ndf::Ltmd(_) => {
                    return Err(Error::new(ErrorKind::InvalidArgument, "a spatially varying roughness applies to beckmann, ggx, gtr and gpss media, not to a transformed distribution"))
                }
            };
        }
        if let Some(scale) = local.reflectance_scale {
            m.phase.micro_bsdf = self.phase.micro_bsdf.with_reflectance_scale(scale)?;
        }
        // The seeds/000 Eq. 40 mixture mixes in the Beckmann limit of one gpss distribution: the
        // local one (sampling the medium's own gave pdf 0 where the local phase function is not
        // 0, found by fuzzing), or exact sampling for an anisotropy matrix, which has no such limit.
        if let VndfSampling::Mixture(mix) = self.phase.sampling {
            m.phase.sampling = match m.phase.ndf {
                Ndf::Gpss(gpss) => VndfSampling::Mixture(BeckmannUniformMixture { ndf: gpss, ratio: mix.ratio }),
                _ => VndfSampling::Exact,
            };
        }
        Ok(m)
    }

    /// The isotropic distribution of this medium's family with roughness `alpha` along every
    /// axis: the projected area seen from any direction grows with every roughness (
    /// seeds/000 Eq. 32 for Gaussian gradients; GGX's Λ grows with α), so this bounds the field's NDFs
    /// whose roughnesses lie below `alpha`.
    pub fn isotropic_ndf(&self, alpha: f64) -> Ndf {
        match self.phase.ndf {
            Ndf::Beckmann(_) => Ndf::Beckmann(Beckmann { alpha_u: alpha, alpha_v: alpha }),
            Ndf::Ggx(_) => Ndf::Ggx(Ggx { alpha_u: alpha, alpha_v: alpha }),
            Ndf::Gpss(_) | Ndf::GpssMatrix(_) => Ndf::Gpss(Gpss { alpha_x: alpha, alpha_y: alpha, alpha_z: alpha }),
            // (a zero roughness bound is kept a hair above zero: M must stay invertible)
            Ndf::Gtr(g) => match Ltmd::new(LtmdBase::Gtr(g), DMat2::from_diagonal(DVec2::splat((alpha / g.alpha).max(1e-150)))) {
                Ok(l) => Ndf::Ltmd(l),
                Err(_) => Ndf::Gtr(g),
            },
            // (localized refuses a varying roughness for transformed distributions)
            Ndf::Ltmd(l) => Ndf::Ltmd(l),
        }
    }
}
