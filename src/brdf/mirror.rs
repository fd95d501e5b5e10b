//! Perfect specular reflection (a delta distribution).
//!
//! Parameter: `reflectance` R (linear RGB, each channel in [0, 1]).
//!
//! As a delta lobe it has no density: `eval` and `pdf` are 0 for every pair
//! of directions, and `sample` returns the mirror direction with weight R and
//! `specular = true`. The directionality analysis gives it the floor
//! `alpha_min` without sampling.

use super::phong::check_rgb01;
use super::BrdfSample;
use crate::error::Result;
use crate::sampling::reflect_z;
use glam::Vec3;

/// A perfect mirror.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mirror {
    reflectance: Vec3,
}

impl Mirror {
    /// A mirror of reflectance `r`.
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] when a channel is NaN or outside [0, 1].
    pub fn new(r: Vec3) -> Result<Self> {
        Ok(Mirror {
            reflectance: check_rgb01("mirror reflectance", r)?,
        })
    }

    /// The reflectance.
    pub fn reflectance(&self) -> Vec3 {
        self.reflectance
    }

    /// Always 0: a delta lobe has no finite value.
    pub fn eval(&self, _wi: Vec3, _wo: Vec3) -> Vec3 {
        Vec3::ZERO
    }

    /// The mirror direction, weight R.
    pub fn sample(&self, wi: Vec3, _u: [f32; 2]) -> Option<BrdfSample> {
        if wi.z <= 0.0 {
            return None;
        }
        Some(BrdfSample {
            wo: reflect_z(wi),
            weight: self.reflectance,
            pdf: 0.0,
            specular: true,
        })
    }

    /// Always 0 (delta).
    pub fn pdf(&self, _wi: Vec3, _wo: Vec3) -> f32 {
        0.0
    }

    /// R above the horizon.
    pub fn albedo(&self, wi: Vec3) -> Vec3 {
        if wi.z <= 0.0 {
            Vec3::ZERO
        } else {
            self.reflectance
        }
    }
}
