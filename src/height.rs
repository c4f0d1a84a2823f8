//! The height (signed-distance) statistics of the shell, seeds/000 Eq. 5 and 13.
//!
//! SDF sign (design notes): `f > 0` above/outside the mean surface, `f < 0` inside.
//!
//! **What happens below the shell.** The paper draws the shell as `[-3σ, +3σ]`, but the flake
//! density `ρ(f) = φ(f;0,σ²)/Φ(f;0,σ²)` grows like `|f|/σ²` below the surface, and cutting it at
//! `-3σ` lets about 0.3 % of normally incident light through (design notes). Here the density is
//! **not** cut below: the interior continues with the same `ρ(f)`, so the optical depth to
//! `f -> -∞` is infinite (`ln Φ -> -∞`) and an opaque object stays opaque. Only the top is cut:
//! above `+kσ` (`shell_extent = k`, default 3) the density is zero, which removes the flakes a
//! ray would meet there with probability `1 − Φ(k)` (1.3e-3 for k = 3) — that bounds the region
//! a host must march through.

use crate::error::Result;
use crate::limits::{check_shell_extent, check_sigma};
use crate::special::{ln_normal_cdf, normal_pdf_over_cdf};

/// Default `k` of the `+kσ` top face (seeds/000 Sec. 4 uses 3σ).
pub const DEFAULT_SHELL_EXTENT: f64 = 3.0;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeightProfile {
    /// Standard deviation of the heights (scene units), Eq. 5.
    pub sigma: f64,
    /// `k`: the shell's top face is at `f = k σ`.
    pub shell_extent: f64,
}

impl HeightProfile {
    /// `sigma` within [`crate::limits::SIGMA_RANGE`], `shell_extent` within
    /// [`crate::limits::SHELL_EXTENT_RANGE`].
    pub fn new(sigma: f64, shell_extent: f64) -> Result<HeightProfile> {
        Ok(HeightProfile { sigma: check_sigma("parameter \"sigma\"", sigma)?, shell_extent: check_shell_extent(shell_extent)? })
    }

    /// Signed distance of the shell's top face, `kσ`.
    pub fn top(&self) -> f64 {
        self.shell_extent * self.sigma
    }

    /// `ρ(f) = φ(f;0,σ²) / Φ(f;0,σ²)` (Eq. 13), zero above the top face.
    pub fn density(&self, f: f64) -> f64 {
        if f > self.top() {
            0.0
        } else {
            normal_pdf_over_cdf(f / self.sigma) / self.sigma
        }
    }

    /// `ln Φ(min(f, kσ)/σ)`: an antiderivative of [`Self::density`] in `f`.
    pub fn ln_cdf(&self, f: f64) -> f64 {
        ln_normal_cdf(f.min(self.top()) / self.sigma)
    }
}
