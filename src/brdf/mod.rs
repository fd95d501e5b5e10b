//! Reflection models: a closed set, dispatched by `match` (no trait objects, so
//! work queues hold plain `Copy` values). One file per model.
//!
//! All directions are in the local shading frame (normal = +z) and point away
//! from the surface: `wi` towards where the light came from, `wo` towards where
//! it leaves.

pub mod lambert;

pub use lambert::Lambert;

use glam::Vec3;

/// A BRDF sample: the outgoing direction and its Monte Carlo weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BrdfSample {
    /// Outgoing direction (local frame).
    pub wo: Vec3,
    /// `f_r(wi, wo) cos(theta_o) / pdf(wo)` per RGB channel.
    pub weight: Vec3,
    /// Solid-angle pdf of `wo` (0 for a delta lobe).
    pub pdf: f32,
    /// True when `wo` came from a delta (perfectly specular) lobe.
    pub specular: bool,
}

/// The reflection models a scene may use.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Brdf {
    /// Ideal diffuse.
    Lambert(Lambert),
}

impl Brdf {
    /// `f_r(wi, wo)` per RGB channel (sr^-1); 0 below the horizon.
    pub fn eval(&self, wi: Vec3, wo: Vec3) -> Vec3 {
        match self {
            Brdf::Lambert(b) => b.eval(wi, wo),
        }
    }

    /// Importance-samples `wo` for a given `wi`.
    pub fn sample(&self, wi: Vec3, u: [f32; 2]) -> Option<BrdfSample> {
        match self {
            Brdf::Lambert(b) => b.sample(wi, u),
        }
    }

    /// Solid-angle pdf of [`Brdf::sample`].
    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        match self {
            Brdf::Lambert(b) => b.pdf(wi, wo),
        }
    }

    /// Directional albedo `integral f_r(wi, wo) cos(theta_o) dwo` per channel.
    pub fn albedo(&self, wi: Vec3) -> Vec3 {
        match self {
            Brdf::Lambert(b) => b.albedo(wi),
        }
    }

    /// True when the whole model is a delta distribution (no photon is stored on it).
    pub fn is_delta(&self) -> bool {
        match self {
            Brdf::Lambert(_) => false,
        }
    }
}
