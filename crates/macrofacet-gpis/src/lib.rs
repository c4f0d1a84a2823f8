//! A realization-based ground truth: Gaussian-process implicit surfaces (GPIS) rendered by ray
//! marching *in function space*, after Seyb, d'Eon, Bitterli and Jarosz 2024 (seeds/004). This is
//! the reference the macrofacet medium is validated against (seeds/000 Fig. 7 and 10; design
//! notes, validation target 7). Nothing here is fast; everything here is (nearly) exact.
//!
//! ## The process
//! `f ~ GP(μ, k)` over `R³` with `μ` a signed distance function given by the caller
//! ([`MeanSdf`]: [`Plane`], [`Sphere`]) and the squared-exponential kernel [`SeKernel`] of
//! seeds/000 Eq. 1 (variance `σ²`, correlation lengths `(l_x, l_y, l_z)` in the local frame,
//! `l_z = +∞` = a height field). Crate conventions: local frame normal `+z`, `f > 0` outside,
//! `α_i = √2 σ / l_i`. Each realization's zero level set is one surface; its normals are
//! `∇f/|∇f|` (seeds/004 Sec. 3.2), pointing outward.
//!
//! With a field ([`GpisTracer::with_field`], the [`MediumField`] the macrofacet tracker takes)
//! the kernel is the non-stationary kernel of seeds/004 Eqs. 25–26 whose local `σ(x)` and
//! anisotropy `Σ(x)` the field gives ([`FieldKernel`], which says how `sigma`, `alpha` and
//! `anisotropy` map to it). The march is the same; its steps follow the local kernel, the
//! envelope is drawn at the field's `sigma_max`, and each observation keeps its point's local
//! kernel ([`Covariance::Local`]).
//!
//! ## Ray marching in function space (seeds/004 Sec. 4.2, Algorithm 1, Fig. 8)
//! [`GpisTracer::trace`] follows the ray `x(t) = o + t d` (`d` = *propagation* direction, unit):
//! 1. **Envelope.** While the mean is above the envelope `μ > E σ` (`E` =
//!    [`MarchSettings::envelope`], default 6: the prior probability of being inside there is
//!    `Φ(−6) ≈ 1e-9`) the ray is advanced by sphere tracing on `μ` without sampling (Fig. 8's
//!    conservative envelope); a ray outside the envelope that moves away from the mean surface
//!    (`d · ∇μ ≥ 0`) has escaped. Exact for convex means (plane, sphere).
//! 2. **Sampling the 1-D process** (seeds/004 Eq. 14, step (1) of Sec. 4.2): values at `t_j = t_0 + jΔt`
//!    are drawn one at a time from the Gaussian conditioned on the memory at the origin and on
//!    the previous samples of the segment (seeds/000 Eq. 3, seeds/004 Sec. 3.1.3–3.1.4).
//!    `Δt` solves `k(x, x + Δt d)/k(x, x) = ρ` with `ρ =` [`STEP_CORRELATION`] `= 0.95`, capped
//!    at [`MarchSettings::max_step`]` · σ` (a vertical ray in a height field is perfectly
//!    correlated and would otherwise take one infinite step).
//! 3. **Window.** A segment conditions on all its samples up to `W` of them
//!    (`W =` [`MarchSettings::window`], default 64, i.e. `≈ 20 l` along an axis — every segment
//!    that crosses a shell of a few `σ` fits); beyond, the oldest half is forgotten and the
//!    factor rebuilt (the memory at the origin is never forgotten). This is Fig. 8's "n samples
//!    per segment, then continue with a new set of conditioned samples", with the new set still
//!    conditioned on the `W/2` most recent samples. The error is that of dropping samples more
//!    than `W/2` steps back, whose correlation with the next point is `≤ ρ^{(W/2)²}` (`2e-23`
//!    for `W = 64`). Short windows are *not* harmless for an analytic kernel, whose conditional
//!    law hinges on high-order differences of many samples: a sliding window of the last 8
//!    samples gave a spurious correlation of −0.35 at a lag of 19 steps (true value 0), and the
//!    evict-half scheme with `W = 8` (keeping 4) −0.08 at lag 12; with `W = 24` the covariance
//!    matches `k` at every lag up to 39 steps (`tests/gpis.rs`). Appending a sample extends the
//!    Cholesky factor by one row in `O(n²)`.
//! 4. **Crossing.** The first sample with `f ≤ 0` brackets the crossing. The bracket is halved
//!    [`MarchSettings::bisection_levels`] times by *conditioned* samples at its midpoint
//!    (default 6: the bracket shrinks to `Δt/64 ≈ 0.005 l`), then the crossing is placed by
//!    linear interpolation. Crossings that dip below zero *between* two positive samples are
//!    missed; with `ρ = 0.95` that is rare (the tests bound its effect on the transmittance
//!    through the comparison with `ρ = 0.99`).
//! 5. **Normal** (step (3) of Sec. 4.2, seeds/004 Eq. 6): the gradient at the crossing `x_c` is drawn
//!    from its Gaussian law conditioned on the memory, the window, the bisection samples and
//!    `f(x_c) = 0`, with the directional derivative `d · ∇f` truncated to negative values (an
//!    entering crossing, `f` goes from `+` to `−`). The normal `∇f/|∇f|` then faces the incoming
//!    ray: `n · d < 0` (if a degenerate conditional law still gives `n · d > 0` it is flipped).
//!
//! ## Memory models (seeds/004 Sec. 4.1) and start states
//! - [`StartState::Uncorrelated`]: a ray from free space (camera, light, non-GPIS surface): the
//!   origin value is drawn from the prior *conditioned on `f(o) > 0`* (the `ζ_u` of seeds/004
//!   Sec. 5.3 / the conditioning of Sec. 5.1), a truncated normal. An origin above the envelope
//!   is first moved to the envelope (step 1), where the truncation is immaterial (`Φ(−6)`).
//! - [`StartState::Unconditioned`]: the origin value is drawn from the prior with no condition;
//!   if it is `≤ 0` the ray starts inside and the origin itself is returned as the crossing
//!   (with a normal drawn as in step 5).
//! - [`StartState::OnSurface`] after a crossing `x_k`: [`Memory::Renewal`] conditions the next
//!   segment only on `f(x_k) = 0` (Sec. 4.1.2); [`Memory::RenewalPlus`] also on
//!   `∇f(x_k) = g_k` (Sec. 4.1.3). The paper writes the condition with the normal `n_k`; the
//!   gradient is not unit length, so the full sampled gradient `g_k` (kept in
//!   [`Crossing::gradient`]) is what is conditioned on — the exact law of `f` near `x_k` given
//!   the last crossing's value and gradient. Components along axes with `l_i = ∞` are
//!   deterministic (`∂_i μ`) and are not conditioned on.
//!   The Global-n models are not implemented.
//!
//! ## Numerics
//! The Gram matrix of the observations (`≤ 4 + W + levels + 1` rows) is factored with a
//! Cholesky carrying a relative nugget [`DEFAULT_JITTER`] `· K_ii` that grows ×100 on failure
//! ([`linalg`]) and is extended row by row as samples arrive; variances are clamped at 0, and
//! normals are drawn with [`macrofacet::special::probit`] from the caller's uniform numbers
//! (`[0, 1)`; this module keeps no generator: the C ABI's `mf_gpis_trace` draws them from a PCG32
//! it seeds with the host's per-call seed). Rays never produce NaN: a march that exceeds
//! [`MarchSettings::max_points`] samples returns [`Trace::Exhausted`] (tiny lengthscales make
//! tiny steps).
//!
//! ## What the tests measured (σ = 1, α = 1, `tests/gpis.rs`)
//! - Transmittance at 45° from `f0 = 3σ` (seeds/000 Fig. 7): the height field is below the
//!   Beckmann macrofacet by at most 0.007 (in the lower half of the shell: −0.0064 ± 0.0008 at
//!   `f = −0.9σ` with 200 000 realizations in the validation report, §1, as the README says; the
//!   test's 20 000 realizations print up to −0.0098, one of their standard errors (≤ 0.0036) away);
//!   the isotropic kernel matches the generalized macrofacet to 0.004 for `h ≥ 1σ` and drifts to
//!   −0.015 below. `ρ = 0.99` changes the curve by ≤ 0.006 (≈ its standard error).
//! - First-hit normals vs the Smith/macrofacet vNDF (Fig. 10) at 0°, 45°, 75°: histogram total
//!   variation within 0.012 of the Monte Carlo floor; at 45° the mean GPIS normal leans
//!   0.007 ± 0.002 further toward the viewer than Smith's (unchanged with `ρ = 0.99` and 10
//!   bisection levels, so not a discretisation artefact: the slope–visibility correlation that
//!   Smith ignores). At grazing incidence (70°–80°) the default `ρ = 0.95` does bias first-hit
//!   normals by about −0.004 in the mean normal (3–4 standard errors against a brute-force
//!   sampler in the validation report): it misses crossings where a realization just grazes the
//!   ray between samples. Use `step_correlation = 0.99` for grazing normals.
//!
//! ## With fields (`tests/gpis_fields.rs`)
//! - Gram matrices of values and gradients on random point sets (smooth anisotropy, smooth
//!   roughness, stepped σ and α, height fields) have no eigenvalue below −3e-17 × the largest;
//!   the kernel without seeds/004 Eq. 25's prefactor gives −6e-2. Derivative covariances match finite
//!   differences of the kernel to 5e-8. Realizations' covariance across a step and a ramp
//!   matches the kernel within 2.4 SE (300 pairs).
//! - A field of the medium's own (or of constant) parameters gives the stationary crossings bit
//!   for bit; so does a piecewise-constant field for rays that stay in one region.
//! - Planar GPSS, σ 0.5 | 1 across `x = 0` at fixed `α = 1`, 45°: per region and across a ramp
//!   11 lengthscales wide, realizations vs the macrofacet tracker with the same field differ as
//!   in the stationary case (≤ 0.015 down to the mean plane). Across a sharp step the
//!   realizations jump (seeds/004 Eq. 25's `σ(x)σ(y)`): going up the step their transmittance falls 0.16
//!   below the tracker's just past it (z ≈ −45), going down it rises up to 0.045 above (z ≈ +11)
//!   — cliffs that the local-stationary medium `ρ(f; σ(x))` does not represent.

// `!(x > 0.0)` is used on purpose, as in the core: unlike `x <= 0.0` it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod experiments;
mod kernel;
pub mod linalg;
mod surface;
pub use surface::GpisSurface;
mod mean;
mod nonstationary;
pub mod params;

pub use experiments::{mirror_random_walk, transmittance_curve, visible_normals, GpisWalk, TransmittanceEstimate};
pub use kernel::{Covariance, Functional, SeKernel};
pub use mean::{MeanSdf, Plane, Sphere};
pub use nonstationary::{sigma_max, FieldKernel, LocalKernel};
pub use params::gpis_from_params;

use macrofacet::error::{Error, ErrorKind, Result};
use macrofacet::field::{Constant, LocalParams, MediumField};
use macrofacet::special::{ln_normal_cdf, probit, probit_of_ln};
use glam::DVec3;
use std::cell::Cell;

/// The correlation between successive samples along a ray, `k(x, x+Δt d)/k(x, x)` (Sec. 4.2.1
/// of seeds/004 spaces samples "appropriately for the given covariance function"; 0.95 gives
/// `Δt ≈ 0.32 l` along an axis).
pub const STEP_CORRELATION: f64 = 0.95;
/// Default cap on the samples a segment conditions on (module documentation, step 3).
pub const DEFAULT_WINDOW: usize = 64;
/// Default relative nugget of every Cholesky factorisation ([`linalg`]).
pub const DEFAULT_JITTER: f64 = 1e-9;
/// Further bisection levels while a crossing's bracket still starts at an on-surface origin
/// (`GpisTracer::locate`): 10 more halve the default bracket (`Δt/64 ≈ 0.005 l`) down to
/// `≈ 5e-6 l`, where the difference between neighbouring values (`∝ t`) meets the noise of
/// the `1e-9` relative nugget (`≈ 3e-5 σ`), so deeper samples would decide nothing.
pub const EXTRA_START_LEVELS: u32 = 10;
/// Bound of [`GpisTracer::check_start_gradient`], in standard deviations of the prior slope.
pub const START_GRADIENT_DEVIATIONS: f64 = 40.0;

/// Which state of the last crossing the next segment remembers (seeds/004 Sec. 4.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Memory {
    /// `f(x_k) = 0` only (Sec. 4.1.2).
    Renewal,
    /// `f(x_k) = 0` and `∇f(x_k) = g_k` (Sec. 4.1.3).
    RenewalPlus,
}

/// What a segment's origin is conditioned on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StartState {
    /// Free-space origin, `f(o) > 0` (seeds/004 `ζ_u`); truncated-normal origin value.
    Uncorrelated,
    /// Free-space origin with no condition at all (the prior).
    Unconditioned,
    /// The origin is a crossing: `f(o) = 0`, and `∇f(o) = gradient` when given (Renewal+).
    OnSurface { gradient: Option<DVec3> },
}

impl StartState {
    /// The start state of the segment leaving crossing `c` under `memory`.
    pub fn after(c: &Crossing, memory: Memory) -> StartState {
        match memory {
            Memory::Renewal => StartState::OnSurface { gradient: None },
            Memory::RenewalPlus => StartState::OnSurface { gradient: Some(c.gradient) },
        }
    }
}

/// The first entering zero crossing of a realization along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing {
    /// Distance along the ray.
    pub t: f64,
    /// `o + t d`.
    pub point: DVec3,
    /// The sampled gradient `∇f(point)` (not normalised; Renewal+ conditions on it).
    pub gradient: DVec3,
    /// `gradient/|gradient|`, outward; `normal · d < 0`.
    pub normal: DVec3,
    /// The field's parameters at the crossing (none without a field): what the reflection there
    /// uses (`reflectance_scale`).
    pub local: LocalParams,
}

/// The result of [`GpisTracer::trace`].
// (A crossing is larger than the other outcomes; boxing it would allocate per ray.)
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Trace {
    /// The first entering crossing.
    Hit(Crossing),
    /// No crossing before `t_max`, or the ray left the envelope moving away from the surface.
    Miss,
    /// The march took [`MarchSettings::max_points`] samples without deciding (reached `t`).
    Exhausted { t: f64 },
    /// The mean ([`MeanSdf`]) returned a NaN or infinite value or gradient at `point`; the
    /// march stopped at the first such answer.
    InvalidMean { point: DVec3 },
}

impl Trace {
    /// The crossing, if any.
    pub fn crossing(self) -> Option<Crossing> {
        match self {
            Trace::Hit(c) => Some(c),
            _ => None,
        }
    }
}

/// Discretisation settings of the march (module documentation, steps 1–4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MarchSettings {
    /// `ρ`: successive samples have correlation `ρ` ([`STEP_CORRELATION`]).
    pub step_correlation: f64,
    /// Largest step in units of `σ` (default 1).
    pub max_step: f64,
    /// Cap on the samples of a segment conditioned on; beyond it the oldest half is forgotten
    /// (default [`DEFAULT_WINDOW`]; at least 2).
    pub window: usize,
    /// Conditioned bisection steps locating a crossing (default 6).
    pub bisection_levels: u32,
    /// Envelope `E`: above `μ = E σ` nothing is sampled (default 6).
    pub envelope: f64,
    /// Cap on samples per trace (default 100 000).
    pub max_points: usize,
    /// Relative Cholesky nugget (default [`DEFAULT_JITTER`]).
    pub jitter: f64,
}

impl Default for MarchSettings {
    fn default() -> Self {
        MarchSettings {
            step_correlation: STEP_CORRELATION,
            max_step: 1.0,
            window: DEFAULT_WINDOW,
            bisection_levels: 6,
            envelope: 6.0,
            max_points: 100_000,
            jitter: DEFAULT_JITTER,
        }
    }
}

/// A GPIS `GP(μ, k)` and the settings to march rays through its realizations. The kernel is the
/// stationary `kernel`, or, with a field ([`GpisTracer::with_field`]), the non-stationary kernel
/// of seeds/004 Eqs. 25–26 whose local parameters the field gives, `kernel` supplying what the
/// field leaves unset ([`FieldKernel`]).
#[derive(Clone, Copy, Debug)]
pub struct GpisTracer<'a, M: MeanSdf, F: MediumField = Constant> {
    pub mean: &'a M,
    pub kernel: SeKernel,
    pub field: &'a F,
    pub settings: MarchSettings,
}

/// The field of a stationary GPIS.
const CONSTANT: Constant = Constant;

/// A standard normal from one uniform number in `[0, 1)` (probit; `u = 0` is nudged inward).
pub fn standard_normal(uniform: &mut impl FnMut() -> f64) -> f64 {
    let u = uniform();
    let u = if u.is_nan() { 0.5 } else { u.clamp(f64::MIN_POSITIVE, 1.0 - f64::EPSILON / 2.0) };
    probit(u)
}

/// The observations a segment conditions on — the memory first, then the segment's samples,
/// then bisection samples — with an incrementally maintained Cholesky factor `L` of their Gram
/// matrix (plus the relative nugget) and `α = L⁻¹ r`, `r` = residuals `observed − prior mean`.
/// Appending a sample costs `O(n²)`; forgetting the oldest half of the window refactors once.
/// Each observation keeps the kernel's data at its point.
struct Conditioning<'t, M: MeanSdf, K: Covariance> {
    kernel: &'t K,
    mean: &'t M,
    /// Requested relative nugget.
    jitter: f64,
    /// Relative nugget in use (grows if a factorisation failed).
    eps: f64,
    window_cap: usize,
    memory_len: usize,
    obs: Vec<(Functional, f64, K::Local)>,
    l: Vec<Vec<f64>>,
    alpha: Vec<f64>,
    /// Where the mean first answered NaN or infinity, if it did.
    invalid_mean: Cell<Option<DVec3>>,
}

impl<'t, M: MeanSdf, K: Covariance> Conditioning<'t, M, K> {
    /// The mean of `a`; a non-finite answer of the mean is remembered in `invalid_mean` (the
    /// march ends with [`Trace::InvalidMean`]).
    fn prior_mean(&self, a: &Functional) -> f64 {
        let value = match *a {
            Functional::Value(p) => self.mean.value(p),
            Functional::Partial(p, i) => self.mean.gradient(p)[i],
        };
        if !value.is_finite() && self.invalid_mean.get().is_none() {
            self.invalid_mean.set(Some(a.point()));
        }
        value
    }

    /// Variance of a functional plus its nugget (the diagonal entry of the factored matrix).
    fn jittered_variance(&self, a: &Functional, la: &K::Local) -> f64 {
        let v = self.kernel.variance(a, la);
        if v > 0.0 {
            v * (1.0 + self.eps)
        } else {
            let sigma = self.kernel.sigma(la);
            self.eps * sigma * sigma
        }
    }

    /// `v = L⁻¹ k(obs, a)`.
    fn solve_k(&self, a: &Functional, la: &K::Local) -> Vec<f64> {
        let mut v: Vec<f64> = self.obs.iter().map(|o| self.kernel.covariance(&o.0, &o.2, a, la)).collect();
        for i in 0..v.len() {
            let row = &self.l[i];
            let s = v[i] - row[..i].iter().zip(&v[..i]).map(|(x, y)| x * y).sum::<f64>();
            v[i] = s / row[i];
        }
        v
    }

    fn refactor(&mut self) {
        let n = self.obs.len();
        let mut k = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..=i {
                let c = self.kernel.covariance(&self.obs[i].0, &self.obs[i].2, &self.obs[j].0, &self.obs[j].2);
                k[i * n + j] = c;
                k[j * n + i] = c;
            }
        }
        let chol = linalg::cholesky_jittered(&k, n, self.jitter);
        self.eps = chol.jitter;
        let residuals: Vec<f64> = self.obs.iter().map(|o| o.1).collect();
        self.alpha = chol.forward(&residuals);
        self.l = (0..n).map(|i| chol.l[i * n..i * n + i + 1].to_vec()).collect();
    }

    /// Adds the observation `a = observed` (kernel data `la`); `v` is `L⁻¹ k(obs, a)` if already
    /// computed.
    fn append(&mut self, a: Functional, la: K::Local, observed: f64, v: Option<Vec<f64>>) {
        let r = observed - self.prior_mean(&a);
        let v = v.unwrap_or_else(|| self.solve_k(&a, &la));
        let d = self.jittered_variance(&a, &la) - v.iter().map(|x| x * x).sum::<f64>();
        self.obs.push((a, r, la));
        if d > 0.0 && d.is_finite() && r.is_finite() {
            let ld = d.sqrt();
            let va = v.iter().zip(&self.alpha).map(|(x, y)| x * y).sum::<f64>();
            self.alpha.push((r - va) / ld);
            let mut row = v;
            row.push(ld);
            self.l.push(row);
        } else {
            self.refactor(); // grows the nugget as needed
        }
    }

    fn observe_memory(&mut self, a: Functional, la: K::Local, observed: f64) {
        self.append(a, la, observed, None);
        self.memory_len = self.obs.len();
    }

    /// Forgets the oldest half of the segment's samples once there are more than the cap.
    fn evict_if_needed(&mut self) {
        let window = self.obs.len() - self.memory_len;
        if window > self.window_cap {
            let keep = (self.window_cap / 2).max(1);
            self.obs.drain(self.memory_len..self.obs.len() - keep);
            self.refactor();
        }
    }

    /// Conditional mean and covariance (row-major) of `targets` given every observation.
    fn predict(&self, targets: &[(Functional, K::Local)]) -> (Vec<f64>, Vec<f64>) {
        let m = targets.len();
        let v: Vec<Vec<f64>> = targets.iter().map(|(t, lt)| self.solve_k(t, lt)).collect();
        let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>();
        let mean: Vec<f64> = targets.iter().zip(&v).map(|((t, _), vt)| self.prior_mean(t) + dot(vt, &self.alpha)).collect();
        let mut cov = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..m {
                cov[i * m + j] = self.kernel.covariance(&targets[i].0, &targets[i].1, &targets[j].0, &targets[j].1) - dot(&v[i], &v[j]);
            }
            cov[i * m + i] = cov[i * m + i].max(0.0);
        }
        (mean, cov)
    }

    /// Draws `f(p)` (kernel data `lp`) from its conditional law and appends it to the
    /// observations.
    fn sample_value(&mut self, p: DVec3, lp: K::Local, uniform: &mut impl FnMut() -> f64) -> f64 {
        let a = Functional::Value(p);
        let v = self.solve_k(&a, &lp);
        let mean = self.prior_mean(&a) + v.iter().zip(&self.alpha).map(|(x, y)| x * y).sum::<f64>();
        let var = (self.kernel.variance(&a, &lp) - v.iter().map(|x| x * x).sum::<f64>()).max(0.0);
        let f = mean + var.sqrt() * standard_normal(uniform);
        self.append(a, lp, f, Some(v));
        f
    }
}

/// A conditioned value that came out non-finite at `p`: a non-finite mean met on the way (the
/// march reports it as [`Trace::InvalidMean`]), else parameters whose conditional law
/// overflows (a field's lengthscales or variances at the ends of f64's range).
fn degenerate<M: MeanSdf, K: Covariance>(c: &Conditioning<'_, M, K>, p: DVec3) -> Result<Trace> {
    match c.invalid_mean.get() {
        Some(point) => Ok(Trace::InvalidMean { point }),
        None => Err(degenerate_field(p)),
    }
}

fn degenerate_field(p: DVec3) -> Error {
    Error::new(ErrorKind::InvalidArgument, format!("the gpis field's parameters near {p} make the process degenerate"))
}

impl<'a, M: MeanSdf> GpisTracer<'a, M> {
    /// A stationary GPIS with default [`MarchSettings`].
    pub fn new(mean: &'a M, kernel: SeKernel) -> Self {
        GpisTracer::with_field(mean, kernel, &CONSTANT)
    }
}

impl<'a, M: MeanSdf, F: MediumField> GpisTracer<'a, M, F> {
    /// A GPIS whose kernel's local parameters `field` gives ([`FieldKernel`]; `kernel` for what
    /// it leaves unset), with default [`MarchSettings`]. The field's `sigma_max` must bound its
    /// `σ` (the envelope is drawn at it); a trace that meets a larger one fails.
    pub fn with_field(mean: &'a M, kernel: SeKernel, field: &'a F) -> Self {
        GpisTracer { mean, kernel, field, settings: MarchSettings::default() }
    }

    /// The largest `σ` of the process: the field's `sigma_max`, else the kernel's `σ`.
    pub fn sigma_max(&self) -> f64 {
        sigma_max(&self.kernel, self.field)
    }

    /// The stationary step along `d`: `Δt` of [`MarchSettings::step_correlation`], capped at
    /// `max_step · σ` (with a field, steps follow the local kernel).
    pub fn step(&self, d: DVec3) -> f64 {
        self.local_step(&self.kernel, &(), d)
    }

    /// The step at a point whose kernel data is `la`.
    fn local_step<K: Covariance>(&self, kernel: &K, la: &K::Local, d: DVec3) -> f64 {
        let rho = self.settings.step_correlation.clamp(1e-6, 1.0 - 1e-12);
        kernel.step_for_correlation(la, d, rho).min(self.settings.max_step * kernel.sigma(la))
    }

    fn conditioning<'t, K: Covariance>(&'t self, kernel: &'t K, origin: DVec3, start: &StartState) -> Result<Conditioning<'t, M, K>> {
        let mut c = Conditioning {
            kernel,
            mean: self.mean,
            jitter: self.settings.jitter,
            eps: self.settings.jitter.max(1e-15),
            window_cap: self.settings.window.max(2),
            memory_len: 0,
            obs: Vec::new(),
            l: Vec::new(),
            alpha: Vec::new(),
            invalid_mean: Cell::new(None),
        };
        if let StartState::OnSurface { gradient } = *start {
            let lo = kernel.local(origin, gradient.is_some())?;
            c.observe_memory(Functional::Value(origin), lo, 0.0);
            if let Some(g) = gradient {
                for i in 0..3 {
                    if kernel.random_partial(&lo, i) && g[i].is_finite() {
                        c.observe_memory(Functional::Partial(origin, i), lo, g[i]);
                    }
                }
            }
        }
        Ok(c)
    }

    /// Samples the realization at `o + t d` for each `t` of `ts` in order, each value conditioned
    /// on the start state's memory and the window of previous values (steps 2–3 of the module
    /// documentation; no envelope, no truncation: `Uncorrelated` behaves like `Unconditioned`).
    pub fn sample_along(&self, origin: DVec3, d: DVec3, ts: &[f64], start: &StartState, uniform: &mut impl FnMut() -> f64) -> Result<Vec<f64>> {
        if self.field.varies() {
            self.sample_along_with(&FieldKernel::new(self.kernel, self.mean, self.field), origin, d, ts, start, uniform)
        } else {
            self.sample_along_with(&self.kernel, origin, d, ts, start, uniform)
        }
    }

    fn sample_along_with<K: Covariance>(&self, kernel: &K, origin: DVec3, d: DVec3, ts: &[f64], start: &StartState, uniform: &mut impl FnMut() -> f64) -> Result<Vec<f64>> {
        let mut c = self.conditioning(kernel, origin, start)?;
        ts.iter()
            .map(|&t| {
                c.evict_if_needed();
                let p = origin + t * d;
                Ok(c.sample_value(p, kernel.local(p, false)?, uniform))
            })
            .collect()
    }

    /// The first entering crossing along `x(t) = o + t d`, `t ∈ (0, t_max]` (`d` unit, the
    /// propagation direction; `t_max = ∞` allowed). `None` when the ray misses or the march is
    /// exhausted (see [`Self::trace`] to tell those apart).
    pub fn first_crossing(&self, origin: DVec3, d: DVec3, t_max: f64, start: &StartState, uniform: &mut impl FnMut() -> f64) -> Result<Option<Crossing>> {
        Ok(self.trace(origin, d, t_max, start, uniform)?.crossing())
    }

    /// Checks a Renewal+ start gradient before a march conditions on it: along every axis
    /// where the slope is random at the origin, `g_i` must lie within
    /// [`START_GRADIENT_DEVIATIONS`] standard deviations of the prior slope (`σ/l_i = α_i/√2`
    /// for the stationary kernel, seeds/000 Eq. 4; the field's local ones otherwise) about the
    /// mean's slope there. A crossing's sampled gradient always does (beyond 40 deviations a
    /// normal law has mass below 1e-300); a gradient that does not — `DBL_MAX`, say — would
    /// make every conditioned value meaningless (issue 9 item 12). One call to the mean's
    /// gradient.
    ///
    /// With a varying field only finiteness is checked: the slope of the non-stationary process
    /// (seeds/004 Eqs. 25–26) also carries the field's own variation, which a sharp step makes
    /// arbitrarily steep (a crossing at a σ step had a slope 170 prior deviations out); a march
    /// whose conditioned values overflow fails on its own.
    pub fn check_start_gradient(&self, origin: DVec3, gradient: DVec3) -> Result<()> {
        if !gradient.is_finite() {
            return Err(Error::new(ErrorKind::InvalidArgument, format!("start.gradient must be finite, got {gradient}")));
        }
        if self.field.varies() {
            return Ok(());
        }
        let invalid = |message: String| Err(Error::new(ErrorKind::InvalidArgument, message));
        let slope = self.mean.gradient(origin);
        if !slope.is_finite() {
            return invalid(format!("the sdf callback returned a NaN or infinite gradient {slope} at the origin {origin}"));
        }
        // σ/l_i per axis; 0 where the slope is deterministic (l_i = ∞).
        let deviations = self.kernel.sigma * self.kernel.inverse_squared_lengths().map(f64::sqrt);
        for i in 0..3 {
            let deviation = deviations[i];
            let z = (gradient[i] - slope[i]).abs() / deviation;
            if deviation > 0.0 && !(z <= START_GRADIENT_DEVIATIONS) {
                return invalid(format!(
                    "start.gradient component {i} = {} lies {z:.3e} standard deviations ({deviation}) from the mean's slope {} at \
                     the origin: no crossing of this process has that gradient (pass the gradient of the previous mf_gpis_hit)",
                    gradient[i], slope[i]
                ));
            }
        }
        Ok(())
    }

    /// Marches one segment (module documentation, steps 1–5). Invalid input (non-finite origin or
    /// direction, zero direction, NaN `t_max`) gives [`Trace::Miss`]; `d` is normalised. Fails
    /// only when the field does (a callback's failure, invalid parameters, a `σ` above its
    /// `sigma_max`).
    pub fn trace(&self, origin: DVec3, d: DVec3, t_max: f64, start: &StartState, uniform: &mut impl FnMut() -> f64) -> Result<Trace> {
        if !self.field.varies() {
            return self.march(&self.kernel, origin, d, t_max, start, uniform);
        }
        let trace = self.march(&FieldKernel::new(self.kernel, self.mean, self.field), origin, d, t_max, start, uniform)?;
        // Lengthscales or variances at the ends of f64's range make the conditional laws
        // overflow; such a crossing is an error, never a NaN.
        if let Trace::Hit(c) = trace {
            if !(c.t.is_finite() && c.point.is_finite() && c.gradient.is_finite()) {
                return Err(degenerate_field(c.point));
            }
        }
        Ok(trace)
    }

    fn march<K: Covariance>(&self, kernel: &K, origin: DVec3, d: DVec3, t_max: f64, start: &StartState, uniform: &mut impl FnMut() -> f64) -> Result<Trace> {
        let Some(d) = d.try_normalize() else { return Ok(Trace::Miss) };
        if !origin.is_finite() || t_max.is_nan() || !(t_max > 0.0) {
            return Ok(Trace::Miss);
        }
        let mut c = self.conditioning(kernel, origin, start)?;
        let trace = self.march_conditioned(kernel, &mut c, origin, d, t_max, start, uniform);
        // A non-finite mean met as a prior mean of the conditioning (the memory, a sample)
        // overrides whatever the march concluded from it.
        match c.invalid_mean.get() {
            Some(point) => Ok(Trace::InvalidMean { point }),
            None => trace,
        }
    }

    /// The body of [`Self::march`] for a unit `d` and valid `origin`, `t_max`.
    #[allow(clippy::too_many_arguments)]
    fn march_conditioned<K: Covariance>(
        &self,
        kernel: &K,
        c: &mut Conditioning<'_, M, K>,
        origin: DVec3,
        d: DVec3,
        t_max: f64,
        start: &StartState,
        uniform: &mut impl FnMut() -> f64,
    ) -> Result<Trace> {
        let env = self.settings.envelope * kernel.region_sigma();
        let mut t = 0.0;
        // The kernel's data where the march stands (its step starts there).
        let mut here;
        let mut f_prev = match *start {
            StartState::OnSurface { .. } => {
                here = kernel.local(origin, false)?;
                0.0
            }
            StartState::Uncorrelated | StartState::Unconditioned => {
                // Sphere tracing on the mean down to the envelope.
                for _ in 0..10_000 {
                    let x = origin + t * d;
                    let m = self.mean.value(x);
                    if !m.is_finite() {
                        return Ok(Trace::InvalidMean { point: x });
                    }
                    if !(m > env + 1e-3 * kernel.region_sigma()) {
                        break;
                    }
                    let grad = self.mean.gradient(x);
                    if !grad.is_finite() {
                        return Ok(Trace::InvalidMean { point: x });
                    }
                    if d.dot(grad) >= 0.0 {
                        return Ok(Trace::Miss);
                    }
                    t += m - env;
                    if t > t_max {
                        return Ok(Trace::Miss);
                    }
                }
                let x = origin + t * d;
                let m = self.mean.value(x);
                if !m.is_finite() {
                    return Ok(Trace::InvalidMean { point: x });
                }
                here = kernel.local(x, false)?;
                let sigma = kernel.sigma(&here);
                let f0 = if *start == StartState::Uncorrelated {
                    // Truncated to f > 0: z > a = −m/σ, by inverting the upper tail.
                    let a = -m / sigma;
                    let ln_tail = ln_normal_cdf(-a);
                    let v = 1.0 - uniform(); // (0, 1]
                    let zz = -probit_of_ln(v.ln() + ln_tail);
                    // f = m + σ z > 0 for z > a, but with the mean far inside (m ≪ −σ) the excess
                    // σ (z − a) ~ σ/a lies below the rounding of m and the sum can come out ≤ 0
                    // (found by fuzzing: a free start reported a hit at t = 0); the smallest
                    // positive value is then the truncated sample as f64 resolves it.
                    let f = if zz.is_finite() { m + sigma * zz.max(a) } else { m.max(0.0) };
                    f.max(f64::MIN_POSITIVE)
                } else {
                    m + sigma * standard_normal(uniform)
                };
                c.append(Functional::Value(x), here, f0, None);
                if f0 <= 0.0 {
                    // Unconditioned start inside: the "crossing" is the origin itself.
                    return self.sample_normal(c, x, t, d, uniform);
                }
                f0
            }
        };
        let mut count = 0usize;
        loop {
            if t >= t_max {
                return Ok(Trace::Miss);
            }
            let step = self.local_step(kernel, &here, d);
            let mut t_next = (t + step).min(t_max);
            let mut x = origin + t_next * d;
            let mut there = kernel.local(x, false)?;
            // A shorter correlation length ahead (a field that changes along the ray) shortens
            // the step to it, so that no step spans more than ρ of correlation at either end.
            let ahead = self.local_step(kernel, &there, d);
            if ahead < step {
                t_next = (t + ahead).min(t_max);
                x = origin + t_next * d;
                there = kernel.local(x, false)?;
            }
            let mu = self.mean.value(x);
            if !mu.is_finite() {
                return Ok(Trace::InvalidMean { point: x });
            }
            if mu > env {
                let grad = self.mean.gradient(x);
                if !grad.is_finite() {
                    return Ok(Trace::InvalidMean { point: x });
                }
                if d.dot(grad) >= 0.0 {
                    return Ok(Trace::Miss);
                }
            }
            c.evict_if_needed();
            let f = c.sample_value(x, there, uniform);
            if !f.is_finite() || c.invalid_mean.get().is_some() {
                return degenerate(c, x);
            }
            if f <= 0.0 {
                return self.locate(c, origin, d, (t, f_prev), (t_next, f), uniform);
            }
            t = t_next;
            f_prev = f;
            here = there;
            count += 1;
            if count >= self.settings.max_points {
                return Ok(Trace::Exhausted { t });
            }
        }
    }

    /// Conditioned bisection of the bracket `a = (t_a, f_a ≥ 0)`, `b = (t_b, f_b ≤ 0)`, linear
    /// interpolation, then the normal.
    ///
    /// `f_a = 0` only at the start of an on-surface segment (the conditioning `f(o) = 0`) whose
    /// realization is not positive anywhere in the first bracket: it enters at once (Renewal
    /// forgets the slope at the start; a direction into the remembered surface does so with
    /// Renewal+, e.g. a shadow ray). Interpolating from `(0, 0)` would report `t = 0`, which the
    /// ABI promises never to do (issue 9 item 6). The bisection then goes on, at most
    /// [`EXTRA_START_LEVELS`] levels deeper, while the left end is still the start, and if it
    /// stays there the crossing is reported at the right end `t_b > 0`, the nearest point known
    /// to be inside.
    fn locate<K: Covariance>(
        &self,
        c: &mut Conditioning<'_, M, K>,
        origin: DVec3,
        d: DVec3,
        a: (f64, f64),
        b: (f64, f64),
        uniform: &mut impl FnMut() -> f64,
    ) -> Result<Trace> {
        let ((mut ta, mut fa), (mut tb, mut fb)) = (a, b);
        let levels = self.settings.bisection_levels;
        for level in 0..levels + EXTRA_START_LEVELS {
            if level >= levels && fa != 0.0 {
                break;
            }
            let tm = 0.5 * (ta + tb);
            if !(tm > ta && tm < tb) {
                break; // no representable point left between the ends
            }
            let p = origin + tm * d;
            let f = c.sample_value(p, c.kernel.local(p, false)?, uniform);
            if !f.is_finite() {
                return degenerate(c, p);
            }
            if f > 0.0 {
                (ta, fa) = (tm, f);
            } else {
                (tb, fb) = (tm, f);
            }
        }
        let interpolated = if fa - fb > 0.0 { ta + (tb - ta) * (fa / (fa - fb)).clamp(0.0, 1.0) } else { tb };
        // `interpolated = 0` only from a left end at the start with `f_a = 0` (or one that
        // underflows); see above.
        let tc = if interpolated > 0.0 { interpolated } else { tb };
        let xc = origin + tc * d;
        c.append(Functional::Value(xc), c.kernel.local(xc, false)?, 0.0, None);
        self.sample_normal(c, xc, tc, d, uniform)
    }

    /// Draws `∇f(xc)` given every observation, with `d · ∇f < 0` (truncated normal), and builds
    /// the crossing.
    fn sample_normal<K: Covariance>(&self, c: &mut Conditioning<'_, M, K>, xc: DVec3, tc: f64, d: DVec3, uniform: &mut impl FnMut() -> f64) -> Result<Trace> {
        let lc = c.kernel.local(xc, true)?;
        let targets = [(Functional::Partial(xc, 0), lc), (Functional::Partial(xc, 1), lc), (Functional::Partial(xc, 2), lc)];
        let (mean, cov) = c.predict(&targets);
        let m = DVec3::from_slice(&mean);
        let s = |i: usize, j: usize| cov[i * 3 + j];
        let sd = DVec3::new(
            s(0, 0) * d.x + s(0, 1) * d.y + s(0, 2) * d.z,
            s(1, 0) * d.x + s(1, 1) * d.y + s(1, 2) * d.z,
            s(2, 0) * d.x + s(2, 1) * d.y + s(2, 2) * d.z,
        );
        let var_u = d.dot(sd);
        let trace = s(0, 0) + s(1, 1) + s(2, 2);
        let mu_u = d.dot(m);
        let g = if var_u > 1e-14 * trace && var_u.is_finite() {
            let su = var_u.sqrt();
            // u = d·g < 0  ⇔  z < a = −μ_u/s_u.
            let a = -mu_u / su;
            let v = 1.0 - uniform(); // (0, 1]
            let z = probit_of_ln(v.ln() + ln_normal_cdf(a));
            let z = if z.is_finite() { z.min(a) } else { a };
            let u = (mu_u + su * z).min(0.0);
            let cmean = m + sd * ((u - mu_u) / var_u);
            let mut ccov = vec![0.0; 9];
            for i in 0..3 {
                for j in 0..3 {
                    ccov[i * 3 + j] = s(i, j) - sd[i] * sd[j] / var_u;
                }
            }
            let mut normal = || standard_normal(uniform);
            DVec3::from_slice(&linalg::sample_psd(&cmean.to_array(), &ccov, 3, &mut normal))
        } else {
            let mut normal = || standard_normal(uniform);
            DVec3::from_slice(&linalg::sample_psd(&mean, &cov, 3, &mut normal))
        };
        if !g.is_finite() {
            // The conditional law of the gradient uses the mean's gradient at `xc`.
            return Ok(Trace::InvalidMean { point: xc });
        }
        let mut n = g.try_normalize().unwrap_or(-d);
        if n.dot(d) > 0.0 {
            n = -n;
        }
        Ok(Trace::Hit(Crossing { t: tc, point: xc, gradient: g, normal: n, local: c.kernel.params(&lc) }))
    }
}
