//! From glTF 2.0 metallic-roughness materials to this crate's models.
//!
//! Inputs: `base_color` (linear RGB in [0, 1]), `metallic` in [0, 1],
//! `roughness` (glTF's perceptual roughness) in [0, 1].
//!
//! The mapping, after the glTF specification's reference BRDF (Appendix B):
//! - Beckmann roughness `m = roughness^2` (glTF's `alpha`; Beckmann and GGX
//!   agree on the RMS slope for small values), clamped below at
//!   [`CookTorrance::MIN_ROUGHNESS`];
//! - Fresnel at normal incidence `f0 = mix(0.04, base_color, metallic)`
//!   (0.04 is the glTF dielectric, IOR 1.5);
//! - diffuse base `kd = base_color (1 - metallic)`.
//!
//! Special cases, checked in this order:
//! 1. `metallic = 1` and `m < MIN_ROUGHNESS` (roughness below 0.01) →
//!    [`Mirror`] of reflectance `base_color` (a polished metal);
//! 2. `metallic = 0` and `roughness = 1` → [`Lambert`] of albedo `base_color`
//!    (glTF's default material, and a matte dielectric whose 4 % specular
//!    sheen the photon counts cannot tell from diffuse);
//! 3. otherwise → [`CookTorrance`] with `(m, f0, kd)`.
//!
//! A dielectric with roughness below 0.01 keeps a Cook–Torrance lobe at the
//! minimum roughness (no model here layers a mirror over a diffuse base).

use super::{Brdf, CookTorrance, Lambert, Mirror};
use crate::error::{Error, Result};
use glam::Vec3;

/// Maps glTF `pbrMetallicRoughness` to a [`Brdf`] (see the module docs).
///
/// # Errors
/// [`Error::InvalidParameter`] when a base colour channel, `metallic` or
/// `roughness` is NaN or outside [0, 1].
pub fn from_gltf_pbr(base_color: Vec3, metallic: f32, roughness: f32) -> Result<Brdf> {
    let base_color = super::phong::check_rgb01("gltf baseColorFactor", base_color)?;
    for (name, v) in [
        ("gltf metallicFactor", metallic),
        ("gltf roughnessFactor", roughness),
    ] {
        if !(0.0..=1.0).contains(&v) {
            return Err(Error::param(name, format!("must be in [0, 1], got {v}")));
        }
    }
    let m = roughness * roughness;
    if metallic == 1.0 && m < CookTorrance::MIN_ROUGHNESS {
        return Ok(Mirror::new(base_color)?.into());
    }
    if metallic == 0.0 && roughness == 1.0 {
        return Ok(Lambert::new(base_color)?.into());
    }
    let f0 = Vec3::splat(0.04).lerp(base_color, metallic);
    let kd = base_color * (1.0 - metallic);
    Ok(CookTorrance::new(m.max(CookTorrance::MIN_ROUGHNESS), f0, kd)?.into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn special_cases_and_errors() {
        let c = Vec3::new(0.8, 0.5, 0.2);
        assert!(matches!(from_gltf_pbr(c, 1.0, 0.0), Ok(Brdf::Mirror(_))));
        assert!(matches!(from_gltf_pbr(c, 0.0, 1.0), Ok(Brdf::Lambert(_))));
        assert!(matches!(
            from_gltf_pbr(c, 0.5, 0.5),
            Ok(Brdf::CookTorrance(_))
        ));
        assert!(matches!(
            from_gltf_pbr(c, 0.0, 0.0),
            Ok(Brdf::CookTorrance(_))
        ));
        assert!(from_gltf_pbr(c, f32::NAN, 0.5).is_err());
        assert!(from_gltf_pbr(c, 0.5, 1.5).is_err());
        assert!(from_gltf_pbr(Vec3::splat(-1.0), 0.5, 0.5).is_err());
    }
}
