//! Reflection models: a closed set, dispatched by `match` (no trait objects, so
//! work queues hold plain `Copy` values). One file per model:
//! [`Lambert`], [`Phong`] (modified Phong), [`CookTorrance`] (Beckmann,
//! Schlick, V-cavity), [`Mirror`] (delta); [`from_gltf_pbr`] maps glTF
//! metallic-roughness materials onto them.
//!
//! All directions are in the local shading frame (normal = +z) and point away
//! from the surface: `wi` towards where the light came from, `wo` towards where
//! it leaves.

pub mod cook_torrance;
pub mod gltf_map;
pub mod lambert;
pub mod mirror;
pub mod phong;

pub use cook_torrance::CookTorrance;
pub use gltf_map::from_gltf_pbr;
pub use lambert::Lambert;
pub use mirror::Mirror;
pub use phong::Phong;

use crate::rng::hash2;
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

/// The common end of a non-delta sampler: the sample of direction `wo` with
/// solid-angle pdf `pdf` and BRDF value `f`, or `None` when the pdf is not a
/// positive number or the weight `f cos / pdf` is not finite.
pub(crate) fn weighted_sample(wo: Vec3, pdf: f32, f: Vec3) -> Option<BrdfSample> {
    if pdf.is_nan() || pdf <= 0.0 {
        return None;
    }
    let weight = f * wo.z / pdf;
    weight.is_finite().then_some(BrdfSample {
        wo,
        weight,
        pdf,
        specular: false,
    })
}

/// The reflection models a scene may use.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Brdf {
    /// Ideal diffuse.
    Lambert(Lambert),
    /// Modified Phong (diffuse + normalised power-cosine lobe).
    Phong(Phong),
    /// Cook–Torrance microfacet model with an optional diffuse base.
    CookTorrance(CookTorrance),
    /// Perfect mirror (delta).
    Mirror(Mirror),
}

macro_rules! dispatch {
    ($self:ident, $b:ident => $e:expr) => {
        match $self {
            Brdf::Lambert($b) => $e,
            Brdf::Phong($b) => $e,
            Brdf::CookTorrance($b) => $e,
            Brdf::Mirror($b) => $e,
        }
    };
}

impl Brdf {
    /// `f_r(wi, wo)` per RGB channel (sr^-1); 0 below the horizon.
    pub fn eval(&self, wi: Vec3, wo: Vec3) -> Vec3 {
        dispatch!(self, b => b.eval(wi, wo))
    }

    /// Importance-samples `wo` for a given `wi`.
    #[inline]
    pub fn sample(&self, wi: Vec3, u: [f32; 2]) -> Option<BrdfSample> {
        dispatch!(self, b => b.sample(wi, u))
    }

    /// Solid-angle pdf of [`Brdf::sample`].
    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        dispatch!(self, b => b.pdf(wi, wo))
    }

    /// Directional albedo `integral f_r(wi, wo) cos(theta_o) dwo` per channel.
    pub fn albedo(&self, wi: Vec3) -> Vec3 {
        dispatch!(self, b => b.albedo(wi))
    }

    /// True when the whole model is a delta distribution (no photon is stored on it).
    pub fn is_delta(&self) -> bool {
        matches!(self, Brdf::Mirror(_))
    }

    /// A short name of the model (`lambert`, `phong`, `cook-torrance`, `mirror`).
    pub fn kind(&self) -> &'static str {
        match self {
            Brdf::Lambert(_) => "lambert",
            Brdf::Phong(_) => "phong",
            Brdf::CookTorrance(_) => "cook-torrance",
            Brdf::Mirror(_) => "mirror",
        }
    }

    /// The model's tag and the exact bits of its parameters (-0.0 folded
    /// into 0.0): equal models, and only they, have equal values. The
    /// analysis cache is keyed by it.
    pub fn param_bits(&self) -> (u8, [u32; 7]) {
        let (tag, params): (u8, [f32; 7]) = match self {
            Brdf::Lambert(b) => (1, [b.albedo.x, b.albedo.y, b.albedo.z, 0.0, 0.0, 0.0, 0.0]),
            Brdf::Phong(b) => {
                let (d, s) = (b.kd(), b.ks());
                (2, [d.x, d.y, d.z, s.x, s.y, s.z, b.exponent()])
            }
            Brdf::CookTorrance(b) => {
                let (d, f) = (b.kd(), b.f0());
                (3, [d.x, d.y, d.z, f.x, f.y, f.z, b.roughness()])
            }
            Brdf::Mirror(b) => {
                let r = b.reflectance();
                (4, [r.x, r.y, r.z, 0.0, 0.0, 0.0, 0.0])
            }
        };
        // +0.0 folds -0.0 into 0.0 so equal values give equal bits.
        (tag, params.map(|v| (v + 0.0).to_bits()))
    }

    /// A 64-bit hash of [`Brdf::param_bits`] (seeds, quick keys): distinct
    /// models collide with probability ~2^-64; where a collision must never
    /// matter, key by [`Brdf::param_bits`] itself.
    pub fn key(&self) -> u64 {
        let (tag, bits) = self.param_bits();
        bits.iter().fold(tag as u64, |k, &v| hash2(k, v as u64))
    }
}

impl From<Lambert> for Brdf {
    fn from(b: Lambert) -> Self {
        Brdf::Lambert(b)
    }
}
impl From<Phong> for Brdf {
    fn from(b: Phong) -> Self {
        Brdf::Phong(b)
    }
}
impl From<CookTorrance> for Brdf {
    fn from(b: CookTorrance) -> Self {
        Brdf::CookTorrance(b)
    }
}
impl From<Mirror> for Brdf {
    fn from(b: Mirror) -> Self {
        Brdf::Mirror(b)
    }
}
