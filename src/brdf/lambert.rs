//! Ideal diffuse reflection.
//!
//! Parameters: `albedo` (linear RGB, each channel in [0, 1]).

use super::BrdfSample;
use crate::sampling::{cosine_hemisphere, cosine_hemisphere_pdf};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// `f_r = albedo / pi`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lambert {
    /// Reflectance per channel.
    pub albedo: Vec3,
}

impl Lambert {
    /// A diffuse BRDF of the given albedo.
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] when a channel is NaN or outside [0, 1].
    pub fn new(albedo: Vec3) -> crate::Result<Self> {
        Ok(Lambert {
            albedo: super::phong::check_rgb01("lambert albedo", albedo)?,
        })
    }

    /// Evaluates the BRDF.
    pub fn eval(&self, wi: Vec3, wo: Vec3) -> Vec3 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Vec3::ZERO;
        }
        self.albedo * FRAC_1_PI
    }

    /// Cosine-weighted sample; the weight is the albedo.
    pub fn sample(&self, wi: Vec3, u: [f32; 2]) -> Option<BrdfSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let wo = cosine_hemisphere(u);
        let pdf = cosine_hemisphere_pdf(wo.z);
        if pdf <= 0.0 {
            return None;
        }
        Some(BrdfSample {
            wo,
            weight: self.albedo,
            pdf,
            specular: false,
        })
    }

    /// Pdf of [`Lambert::sample`].
    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z <= 0.0 {
            return 0.0;
        }
        cosine_hemisphere_pdf(wo.z)
    }

    /// The albedo, whatever `wi` (above the horizon).
    pub fn albedo(&self, wi: Vec3) -> Vec3 {
        if wi.z <= 0.0 {
            Vec3::ZERO
        } else {
            self.albedo
        }
    }
}
