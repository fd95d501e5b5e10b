//! The `cos^n` emission profile: radiance `L(theta) = L0 cos^n(theta)` about
//! the surface normal.
//!
//! Parameter: `n`, a real exponent >= 0 (0 is a diffuse emitter; larger is
//! more directional). The emitted direction of a photon follows
//! `L cos(theta)`, i.e. the power-cosine density with exponent `n + 1`.

use crate::error::{check_non_negative, Result};
use crate::sampling::{cos_power_hemisphere, cos_power_hemisphere_pdf};
use glam::Vec3;
use std::f32::consts::PI;

/// A `cos^n` radiance profile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CosN {
    n: f32,
}

impl CosN {
    /// A profile with exponent `n`.
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] when `n` is NaN, infinite or negative.
    pub fn new(n: f32) -> Result<Self> {
        Ok(CosN {
            n: check_non_negative("cosn exponent", n)?,
        })
    }

    /// The exponent.
    pub fn exponent(&self) -> f32 {
        self.n
    }

    /// Relative radiance `cos^n(theta)` in a local direction (0 below the horizon).
    pub fn eval(&self, w: Vec3) -> f32 {
        if w.z <= 0.0 {
            0.0
        } else {
            w.z.powf(self.n)
        }
    }

    /// `integral cos^n(theta) cos(theta) dw = 2 pi / (n + 2)`: power per unit
    /// area per unit `L0`. Exact for every n, so the emitted power is exact.
    pub fn projected_integral(&self) -> f32 {
        2.0 * PI / (self.n + 2.0)
    }

    /// Samples a photon's emitted direction (pdf proportional to `cos^(n+1)`).
    pub fn sample_emission(&self, u: [f32; 2]) -> Vec3 {
        cos_power_hemisphere(self.n + 1.0, u)
    }

    /// Solid-angle pdf of [`CosN::sample_emission`].
    pub fn emission_pdf(&self, w: Vec3) -> f32 {
        cos_power_hemisphere_pdf(self.n + 1.0, w.z)
    }
}
