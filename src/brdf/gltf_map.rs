//! From glTF 2.0 materials to this crate's models: the core
//! metallic-roughness factors and the extensions `KHR_materials_clearcoat`,
//! `KHR_materials_ior`, `KHR_materials_sheen`, `KHR_materials_specular`,
//! `KHR_materials_transmission` and `KHR_materials_volume`.
//!
//! Inputs ([`GltfMaterial`]): `base_color` (linear RGB in [0, 1]), `metallic`
//! in [0, 1], `roughness` (glTF's perceptual roughness) in [0, 1]; the
//! extensions' factors, `None` when the extension is absent.
//!
//! # Opaque materials
//! The specification's own BRDF (Appendix B), [`GltfPbr`]: GGX of
//! `alpha = roughness^2` (clamped below at [`GltfPbr::MIN_ALPHA`]) with
//! height-correlated Smith, Schlick's Fresnel of
//! `f0 = mix(f0_d, base_color, metallic)` with the dielectric
//! `f0_d = ((ior - 1) / (ior + 1))^2` (`KHR_materials_ior`; 0.04 for the
//! default IOR 1.5), and the diffuse base `base_color (1 - metallic)`.
//!
//! `KHR_materials_specular` changes the dielectric's Fresnel term as the
//! extension defines it: with `specularFactor = s` in [0, 1] and
//! `specularColorFactor = c` (RGB, each channel >= 0, and above 1 allowed),
//! `f0_d = min(((ior - 1) / (ior + 1))^2 c, 1) s` per channel and the
//! grazing reflectance `f90_d = s` (1 without the extension). The metal's
//! Fresnel is not touched (`f90 = mix(f90_d, 1, metallic)`), and the
//! diffuse base takes what the strongest channel of the reflection leaves,
//! as the extension's `1 - max_value(F)` does ([`GltfPbr`]): a coloured
//! specular does not tint the base. `s = 0` turns the dielectric's reflection off: its base
//! then reflects all of `base_color`. The extension's textures multiply
//! the factors (`specularTexture`'s alpha, `specularColorTexture`'s sRGB
//! colour) where the scene loader reads them.
//!
//! `KHR_materials_clearcoat` puts a clear coat of weight `clearcoatFactor`
//! and GGX `alpha = clearcoatRoughnessFactor^2` (clamped below at
//! [`GltfPbr::MIN_ALPHA`]) over the opaque material
//! ([`GltfPbr::with_clearcoat`], `brdf/gltf_coat.rs`). A coated matte
//! dielectric is [`GltfPbr`], not [`Lambert`]; a coated polished metal stays
//! a [`Mirror`], its coat dropped (the scene loader warns): a glossy lobe of
//! alpha 1e-3 in its place would store photons on a mirror and weight them
//! by its sharp peak.
//!
//! `KHR_materials_sheen` puts a sheen of colour `sheenColorFactor` (linear
//! RGB) and roughness `sheenRoughnessFactor` (raised to
//! [`GltfPbr::MIN_SHEEN_ROUGHNESS`]) over the base, under the coat
//! ([`GltfPbr::with_sheen`]): `brdf/gltf_sheen.rs`'s Charlie lobe, the
//! base scaled by what the sheen lets through as the extension's albedo
//! scaling says. A black colour (the default) is no sheen. As with the
//! coat, a sheened matte dielectric is [`GltfPbr`], not [`Lambert`] (the
//! sheen is what shows at grazing angles), and a sheened polished metal
//! stays a [`Mirror`], its sheen dropped (the scene loader warns).
//!
//! Beckmann [`super::CookTorrance`] is not used for glTF materials (it stays
//! available to code and to `adaptive-pm analyze`).
//!
//! Special cases, checked in this order:
//! 1. `metallic = 1` and `alpha < MIN_ALPHA` (roughness below 0.032) →
//!    [`Mirror`] of reflectance `base_color` (a polished metal; Schlick's
//!    rise towards white at grazing angles is dropped; a coat or a sheen
//!    is dropped too);
//! 2. `metallic = 0`, `roughness = 1`, every channel of `f0_d` at most
//!    0.04 (IOR at most 1.5, no stronger specular colour), and neither a
//!    coat nor a sheen →
//!    [`Lambert`] of albedo `base_color`: a matte dielectric, whose 4 %
//!    specular reflection the photon counts cannot tell from diffuse. This
//!    is an approximation of the specification's BRDF (whose diffuse base
//!    is weighted by `1 - F_d` and whose specular lobe adds a little at
//!    grazing angles), kept because the paper's scenes are Lambertian and the
//!    diffuse walls of the built-in boxes are glTF materials of this kind;
//! 3. otherwise → [`GltfPbr`].
//!
//! # Glass
//! `transmissionFactor = 1` with `metallic = 0` is glass: [`Dielectric`] when
//! `alpha = roughness^2` is below [`RoughDielectric::MIN_ALPHA`], else [`RoughDielectric`] of
//! GGX `alpha`; both with the IOR, the tint `base_color` (the extension's
//! "tinting") and, from `KHR_materials_volume`:
//! - `thicknessFactor = 0` (the default, or no volume extension): a thin wall
//!   (`thin = true`); it has no interior, so the attenuation is checked and
//!   then has no effect (`sigma_a = 0`);
//! - `thicknessFactor > 0`: the boundary of a refracting volume
//!   (`thin = false`; the mesh must be closed), absorbing
//!   `sigma_a = -ln(attenuationColor) / attenuationDistance` per channel and
//!   world unit: 0 for the default infinite distance, [`f32::MAX`] for a
//!   colour channel of 0. The thickness's value is otherwise unused (a ray
//!   tracer measures the distance travelled).
//!
//! A full metal (`metallic = 1`) transmits nothing whatever its
//! `transmissionFactor`: glTF mixes transmission into the dielectric part
//! alone (`mix(dielectric, metal, metallic)`), so it is the opaque mapping.
//!
//! # Partial transmission
//! `0 < transmissionFactor = t < 1`, or transmission on a partial metal
//! (`0 < metallic = m < 1`), is a mix ([`gltf_lobes`]). glTF's dielectric
//! is `F spec + (1 - F) mix(diffuse, btdf, t)`, and since the specular
//! reflection `F spec` is the same in both parts, that is exactly
//! `(1 - t) opaque + t glass`. The material is `mix(dielectric, metal,
//! m)`, so the glass part's share is `w = (1 - m) t`, and the rest,
//! `m metal + (1 - m)(1 - t) opaque`, is the opaque mapping of metallic
//! `m / (1 - w)`: [`GltfPbr`] is linear in `metallic` (its `f0` and its
//! diffuse weight both are), so the split is exact. The glass part is the
//! glass mapping of the same roughness, IOR and tint. The scene keeps the
//! two parts as two materials and picks one per scattering event
//! ([`crate::scene::TransmissionMix`]). With a volume
//! (`thicknessFactor > 0`) the glass part refracts, and the volume absorbs
//! whatever part scatters at its boundary.
//! [`from_gltf_material`], which returns one BRDF, refuses a mix.
//!
//! `KHR_materials_specular`, `KHR_materials_clearcoat` and
//! `KHR_materials_sheen` shape the opaque part only: the glass part
//! keeps the exact Fresnel term of its IOR and has neither coat nor sheen
//! (the scene loader warns when an extension would change it).
//!
//! The extensions' textures, but `KHR_materials_specular`'s,
//! `KHR_materials_clearcoat`'s weight and roughness textures and
//! `KHR_materials_sheen`'s colour and roughness textures, are ignored
//! (the opaque materials' base colour, metallic-roughness, specular,
//! clear coat and sheen textures are read by the scene loader, which maps
//! each point's factors here).
//!
//! # The IOR
//! Default 1.5. It must be in [1, 4] (the specification allows any value
//! from 1; this crate's models stop at 4), or exactly 0: the specification's
//! "specular-glossiness backwards compatibility mode", an infinite IOR whose
//! Fresnel term is 1 at every angle. No light then enters the surface, so
//! transmission and volume have no effect, and the material is the opaque
//! mapping with `f0_d = 1` (Schlick's Fresnel with `f0 = 1` is 1 everywhere).

use super::{Brdf, Dielectric, GltfPbr, Lambert, Mirror, RoughDielectric};
use crate::error::{Error, Result};
use glam::Vec3;

/// The factors of a glTF material that the mapping reads (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GltfMaterial {
    /// `pbrMetallicRoughness.baseColorFactor` without alpha (linear RGB).
    pub base_color: Vec3,
    /// `pbrMetallicRoughness.metallicFactor`.
    pub metallic: f32,
    /// `pbrMetallicRoughness.roughnessFactor` (perceptual roughness).
    pub roughness: f32,
    /// `KHR_materials_transmission.transmissionFactor`; `None` without the
    /// extension (as 0: opaque).
    pub transmission: Option<f32>,
    /// `KHR_materials_ior.ior`; `None` without the extension (as 1.5).
    pub ior: Option<f32>,
    /// `KHR_materials_volume`; `None` without the extension (a thin wall).
    pub volume: Option<GltfVolume>,
    /// `KHR_materials_specular`; `None` without the extension (as its
    /// defaults: no change).
    pub specular: Option<GltfSpecular>,
    /// `KHR_materials_clearcoat`; `None` without the extension (no coat).
    pub clearcoat: Option<GltfClearcoat>,
    /// `KHR_materials_sheen`; `None` without the extension (no sheen).
    pub sheen: Option<GltfSheen>,
}

/// The factors of `KHR_materials_clearcoat` (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GltfClearcoat {
    /// `clearcoatFactor` in [0, 1]: the coat's weight (0: no coat).
    pub factor: f32,
    /// `clearcoatRoughnessFactor` in [0, 1] (perceptual roughness).
    pub roughness: f32,
}

impl GltfClearcoat {
    /// Checks the factors against the extension's ranges.
    fn check(self) -> Result<Self> {
        for (name, v) in [
            ("gltf clearcoatFactor", self.factor),
            ("gltf clearcoatRoughnessFactor", self.roughness),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return Err(Error::param(name, format!("must be in [0, 1], got {v}")));
            }
        }
        Ok(self)
    }
}

/// The factors of `KHR_materials_sheen` (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GltfSheen {
    /// `sheenColorFactor`: linear RGB, each channel in [0, 1] (black: no
    /// sheen).
    pub color: Vec3,
    /// `sheenRoughnessFactor` in [0, 1] (perceptual roughness).
    pub roughness: f32,
}

impl GltfSheen {
    /// Checks the factors against the extension's ranges.
    fn check(self) -> Result<Self> {
        super::phong::check_rgb01("gltf sheenColorFactor", self.color)?;
        let r = self.roughness;
        if !(0.0..=1.0).contains(&r) {
            return Err(Error::param(
                "gltf sheenRoughnessFactor",
                format!("must be in [0, 1], got {r}"),
            ));
        }
        Ok(self)
    }
}

impl GltfMaterial {
    /// The core factors alone, no extension.
    pub fn new(base_color: Vec3, metallic: f32, roughness: f32) -> Self {
        GltfMaterial {
            base_color,
            metallic,
            roughness,
            transmission: None,
            ior: None,
            volume: None,
            specular: None,
            clearcoat: None,
            sheen: None,
        }
    }
}

/// The factors of `KHR_materials_specular` (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GltfSpecular {
    /// `specularFactor` in [0, 1]: scales the dielectric's reflection at
    /// every angle.
    pub factor: f32,
    /// `specularColorFactor`: linear RGB, each channel finite and >= 0,
    /// multiplying the dielectric's reflectance at normal incidence (the
    /// product is clamped to 1).
    pub color: Vec3,
}

impl Default for GltfSpecular {
    /// The extension's defaults: no change.
    fn default() -> Self {
        GltfSpecular {
            factor: 1.0,
            color: Vec3::ONE,
        }
    }
}

impl GltfSpecular {
    /// Checks the factors against the extension's ranges.
    fn check(self) -> Result<Self> {
        let s = self.factor;
        if !(0.0..=1.0).contains(&s) {
            return Err(Error::param(
                "gltf specularFactor",
                format!("must be in [0, 1], got {s}"),
            ));
        }
        let c = self.color;
        if !c.is_finite() || c.min_element() < 0.0 {
            return Err(Error::param(
                "gltf specularColorFactor",
                format!("must be finite and >= 0 in every channel, got {c}"),
            ));
        }
        Ok(self)
    }

    /// The dielectric's `(f0_d, f90_d)` over a dielectric of reflectance
    /// `f0` at normal incidence (checked factors).
    fn fresnel(&self, f0: f32) -> (Vec3, f32) {
        if *self == Self::default() {
            // The bits of the model without the extension.
            return (Vec3::splat(f0), 1.0);
        }
        (
            (Vec3::splat(f0) * self.color).min(Vec3::ONE) * self.factor,
            self.factor,
        )
    }
}

/// The factors of `KHR_materials_volume` (its thickness texture is ignored).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GltfVolume {
    /// `thicknessFactor`: 0 for a thin wall, > 0 for a volume boundary.
    pub thickness: f32,
    /// `attenuationDistance` in world units, > 0; [`f32::INFINITY`] (the
    /// default) for no absorption.
    pub attenuation_distance: f32,
    /// `attenuationColor`: what white light becomes after
    /// `attenuation_distance`, each channel in [0, 1].
    pub attenuation_color: Vec3,
}

impl Default for GltfVolume {
    /// The extension's defaults: thin, no absorption.
    fn default() -> Self {
        GltfVolume {
            thickness: 0.0,
            attenuation_distance: f32::INFINITY,
            attenuation_color: Vec3::ONE,
        }
    }
}

impl GltfVolume {
    /// Checks the factors against the extension's ranges.
    fn check(self) -> Result<Self> {
        let t = self.thickness;
        if !(t.is_finite() && t >= 0.0) {
            return Err(Error::param(
                "gltf thicknessFactor",
                format!("must be a finite number >= 0, got {t}"),
            ));
        }
        let d = self.attenuation_distance;
        if d.is_nan() || d <= 0.0 {
            return Err(Error::param(
                "gltf attenuationDistance",
                format!("must be > 0 (absent for no absorption), got {d}"),
            ));
        }
        super::phong::check_rgb01("gltf attenuationColor", self.attenuation_color)?;
        Ok(self)
    }

    /// `sigma_a = -ln(color) / distance` per channel (checked factors): 0 for
    /// an infinite distance, [`f32::MAX`] for a channel of 0 and where the
    /// quotient overflows.
    fn sigma_a(&self) -> Vec3 {
        let d = f64::from(self.attenuation_distance);
        if d.is_infinite() {
            return Vec3::ZERO;
        }
        let per = |c: f32| {
            if c == 0.0 {
                return f32::MAX;
            }
            // `+ 0.0` folds the -0.0 of a channel of 1 into 0.0.
            ((-f64::from(c).ln() / d).min(f64::from(f32::MAX)) + 0.0) as f32
        };
        let c = self.attenuation_color;
        Vec3::new(per(c.x), per(c.y), per(c.z))
    }
}

/// Maps glTF `pbrMetallicRoughness` without extensions to a [`Brdf`]: the
/// opaque mapping of the module docs with the default IOR 1.5.
///
/// # Errors
/// [`Error::InvalidParameter`] when a base colour channel, `metallic` or
/// `roughness` is NaN or outside [0, 1].
pub fn from_gltf_pbr(base_color: Vec3, metallic: f32, roughness: f32) -> Result<Brdf> {
    from_gltf_material(&GltfMaterial::new(base_color, metallic, roughness))
}

/// A glTF material as this crate models it (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GltfLobes {
    /// The whole material, or its opaque part when it transmits partly.
    pub surface: Brdf,
    /// When it transmits partly: `(share, glass)`, the glass part's share
    /// of the scattering and its (thin, specular) model.
    pub transmitted: Option<(f32, Brdf)>,
    /// The factors `surface` is the mapping of: the material's own, or its
    /// opaque part's when it transmits partly (no transmission, metallic
    /// `m / (1 - share)`). Texels modulate these.
    pub surface_factors: GltfMaterial,
}

/// Maps a glTF material with its transmission, IOR and volume extensions to a
/// [`Brdf`] (see the module docs).
///
/// # Errors
/// [`Error::InvalidParameter`] naming the factor and its value when
/// - a base colour channel, `metallic` or `roughness` is NaN or outside [0, 1];
/// - `transmissionFactor` is NaN or outside [0, 1];
/// - `ior` is neither 0 nor in [1, 4];
/// - `thicknessFactor` is negative or not finite, `attenuationDistance` is
///   not > 0, or an `attenuationColor` channel is outside [0, 1];
/// - `specularFactor` is NaN or outside [0, 1], or a `specularColorFactor`
///   channel is negative or not finite;
/// - `clearcoatFactor` or `clearcoatRoughnessFactor` is NaN or outside
///   [0, 1];
/// - a `sheenColorFactor` channel or `sheenRoughnessFactor` is NaN or
///   outside [0, 1];
/// - the material transmits partly (`0 < transmissionFactor < 1`, or
///   transmission on a partial metal, `0 < metallic < 1`), which one BRDF
///   cannot hold ([`gltf_lobes`] maps it; a full metal transmits nothing:
///   its transmission is ignored).
pub fn from_gltf_material(m: &GltfMaterial) -> Result<Brdf> {
    let lobes = gltf_lobes(m)?;
    if let Some((t, _)) = lobes.transmitted {
        return Err(Error::param(
            "gltf transmissionFactor",
            format!(
                "partial transmission (a share {t} of glass) is a mix of two models, not one \
                 BRDF: map it with gltf_lobes"
            ),
        ));
    }
    Ok(lobes.surface)
}

/// Maps a glTF material to its models: one BRDF, or for partial
/// transmission (`0 < transmissionFactor < 1`, or transmission on a
/// partial metal) the opaque part and the glass part with its share
/// (module docs).
///
/// # Errors
/// As [`from_gltf_material`], except that a mix is mapped.
pub fn gltf_lobes(m: &GltfMaterial) -> Result<GltfLobes> {
    let base_color = super::phong::check_rgb01("gltf baseColorFactor", m.base_color)?;
    for (name, v) in [
        ("gltf metallicFactor", m.metallic),
        ("gltf roughnessFactor", m.roughness),
    ] {
        if !(0.0..=1.0).contains(&v) {
            return Err(Error::param(name, format!("must be in [0, 1], got {v}")));
        }
    }
    let transmission = m.transmission.unwrap_or(0.0);
    if !(0.0..=1.0).contains(&transmission) {
        return Err(Error::param(
            "gltf transmissionFactor",
            format!("must be in [0, 1], got {transmission}"),
        ));
    }
    let ior = m.ior.unwrap_or(1.5);
    if !(ior == 0.0 || (1.0..=4.0).contains(&ior)) {
        return Err(Error::param(
            "gltf ior",
            format!(
                "must be in [1, 4], or 0 (the specular-glossiness compatibility mode), got {ior}"
            ),
        ));
    }
    let volume = m.volume.unwrap_or_default().check()?;
    let (f0_d, f90_d) = m
        .specular
        .unwrap_or_default()
        .check()?
        .fresnel(dielectric_f0(ior));
    let coat = m.clearcoat.unwrap_or_default().check()?;
    let sheen = m.sheen.unwrap_or_default().check()?;
    let (metallic, roughness) = (m.metallic, m.roughness);
    let alone = |surface| {
        Ok(GltfLobes {
            surface,
            transmitted: None,
            surface_factors: *m,
        })
    };
    // IOR 0: the Fresnel term is 1, no light enters, nothing is transmitted.
    // A full metal has no dielectric part to transmit through.
    if transmission == 0.0 || ior == 0.0 || metallic == 1.0 {
        return alone(opaque(
            base_color,
            metallic,
            roughness,
            (f0_d, f90_d),
            (coat, sheen),
        )?);
    }
    // The glass part's share, and the rest: the metal and the opaque
    // dielectric, which the opaque mapping mixes linearly in `metallic`.
    let share = (1.0 - metallic) * transmission;
    let rest = metallic + (1.0 - metallic) * (1.0 - transmission);
    let thin = volume.thickness == 0.0;
    let sigma_a = if thin { Vec3::ZERO } else { volume.sigma_a() };
    let alpha = roughness * roughness;
    let glass: Brdf = if alpha < RoughDielectric::MIN_ALPHA {
        Dielectric::new(ior, base_color, sigma_a, thin)?.into()
    } else {
        RoughDielectric::new(alpha, ior, base_color, sigma_a, thin)?.into()
    };
    if rest == 0.0 {
        return alone(glass);
    }
    // `rest` is `metallic` exactly at transmissionFactor 1: a full metal.
    let metal = (metallic / rest).min(1.0);
    Ok(GltfLobes {
        surface: opaque(base_color, metal, roughness, (f0_d, f90_d), (coat, sheen))?,
        transmitted: Some((share, glass)),
        surface_factors: GltfMaterial {
            metallic: metal,
            transmission: None,
            ..*m
        },
    })
}

/// The dielectric Fresnel reflectance at normal incidence of IOR `ior`
/// (checked: 0 or in [1, 4]), computed in f64 so that 1.5 gives exactly
/// `0.04_f32`; 1 for the IOR 0 of the compatibility mode.
fn dielectric_f0(ior: f32) -> f32 {
    if ior == 0.0 {
        return 1.0;
    }
    let r = (f64::from(ior) - 1.0) / (f64::from(ior) + 1.0);
    (r * r) as f32
}

/// The opaque mapping of checked factors (module docs), with dielectric
/// Fresnel reflectance `(f0_d, f90_d)` at normal and grazing incidence,
/// under clear coat `coat` and sheen `sheen` (checked factors).
fn opaque(
    base_color: Vec3,
    metallic: f32,
    roughness: f32,
    (f0_d, f90_d): (Vec3, f32),
    (coat, sheen): (GltfClearcoat, GltfSheen),
) -> Result<Brdf> {
    let alpha = roughness * roughness;
    // A layer over a matte base shows at grazing angles, where Lambert
    // would not.
    let layered = coat.factor > 0.0 || sheen.color.max_element() > 0.0;
    if metallic == 1.0 && alpha < GltfPbr::MIN_ALPHA {
        return Ok(Mirror::new(base_color)?.into());
    }
    if metallic == 0.0 && roughness == 1.0 && f0_d.max_element() <= 0.04 && !layered {
        return Ok(Lambert::new(base_color)?.into());
    }
    let alpha = alpha.max(GltfPbr::MIN_ALPHA);
    let b = GltfPbr::with_specular(base_color, metallic, alpha, f0_d, f90_d)?;
    let coat_alpha = (coat.roughness * coat.roughness).max(GltfPbr::MIN_ALPHA);
    let b = b.with_clearcoat(coat.factor, coat_alpha)?;
    Ok(b.with_sheen(sheen.color, sheen.roughness)?.into())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn glass(roughness: f32) -> GltfMaterial {
        GltfMaterial {
            transmission: Some(1.0),
            ..GltfMaterial::new(Vec3::new(0.9, 0.8, 0.7), 0.0, roughness)
        }
    }

    fn message(m: &GltfMaterial) -> String {
        from_gltf_material(m).unwrap_err().to_string()
    }

    #[test]
    fn special_cases_and_errors() {
        let c = Vec3::new(0.8, 0.5, 0.2);
        assert!(matches!(from_gltf_pbr(c, 1.0, 0.0), Ok(Brdf::Mirror(_))));
        assert!(matches!(from_gltf_pbr(c, 0.0, 1.0), Ok(Brdf::Lambert(_))));
        assert!(matches!(from_gltf_pbr(c, 0.5, 0.5), Ok(Brdf::GltfPbr(_))));
        assert!(matches!(from_gltf_pbr(c, 0.0, 0.0), Ok(Brdf::GltfPbr(_))));
        assert!(from_gltf_pbr(c, f32::NAN, 0.5).is_err());
        assert!(from_gltf_pbr(c, 0.5, 1.5).is_err());
        assert!(from_gltf_pbr(Vec3::splat(-1.0), 0.5, 0.5).is_err());
    }

    #[test]
    fn the_default_ior_is_the_old_constant_and_sets_f0() {
        assert_eq!(dielectric_f0(1.5).to_bits(), 0.04f32.to_bits());
        let c = Vec3::new(0.8, 0.5, 0.2);
        let Ok(Brdf::GltfPbr(b)) = from_gltf_pbr(c, 0.0, 0.5) else {
            panic!("a rough dielectric is the glTF BRDF")
        };
        assert_eq!(b.f0(), Vec3::splat(0.04));
        // An explicit 1.5 is the absent extension.
        let explicit = GltfMaterial {
            ior: Some(1.5),
            ..GltfMaterial::new(c, 0.0, 0.5)
        };
        assert_eq!(from_gltf_material(&explicit).unwrap(), b.into());
        // IOR 2: f0 = (1/3)^2; no longer Lambert at roughness 1.
        let ior2 = |roughness| GltfMaterial {
            ior: Some(2.0),
            ..GltfMaterial::new(c, 0.0, roughness)
        };
        let Ok(Brdf::GltfPbr(b)) = from_gltf_material(&ior2(1.0)) else {
            panic!("a dielectric of IOR 2 shows its sheen")
        };
        assert!((b.f0() - Vec3::splat(1.0 / 9.0)).abs().max_element() < 1e-7);
        // IOR 1.2 reflects less than 1.5: still Lambert.
        let low = GltfMaterial {
            ior: Some(1.2),
            ..GltfMaterial::new(c, 0.0, 1.0)
        };
        assert!(matches!(from_gltf_material(&low), Ok(Brdf::Lambert(_))));
    }

    #[test]
    fn specular_scales_the_dielectric_and_spares_the_metal_and_the_glass() {
        let c = Vec3::new(0.8, 0.5, 0.2);
        let spec = |factor, color| GltfSpecular { factor, color };
        let m = |metallic, roughness, s, transmission| GltfMaterial {
            ior: Some(2.0),
            specular: Some(s),
            transmission,
            ..GltfMaterial::new(c, metallic, roughness)
        };
        // IOR 2: f0 = 1/9; min(f0 c, 1) s per channel, f90 = s.
        let s = spec(0.5, Vec3::new(3.0, 9.0, 18.0));
        let Ok(Brdf::GltfPbr(b)) = from_gltf_material(&m(0.0, 0.5, s, None)) else {
            panic!("a glossy dielectric")
        };
        let want = Vec3::new(1.0 / 3.0, 1.0, 1.0) * 0.5;
        assert!((b.dielectric_f0() - want).abs().max_element() < 1e-6);
        assert_eq!(b.dielectric_f90(), 0.5);
        // A full metal's lobe is its base colour's, f90 = 1.
        let Ok(Brdf::GltfPbr(metal)) = from_gltf_material(&m(1.0, 0.5, s, None)) else {
            panic!("a rough metal")
        };
        assert_eq!((metal.f0(), metal.f90()), (c, 1.0));
        // Glass keeps its IOR's Fresnel; the opaque part of a mix takes it.
        let glass = gltf_lobes(&m(0.0, 0.5, s, Some(1.0))).unwrap();
        assert!(matches!(glass.surface, Brdf::RoughDielectric(d) if d.ior() == 2.0));
        let mix = gltf_lobes(&m(0.0, 0.5, s, Some(0.5))).unwrap();
        let Brdf::GltfPbr(opaque) = mix.surface else {
            panic!("the opaque part")
        };
        assert_eq!(opaque.dielectric_f0(), b.dielectric_f0());
        // The defaults are the absent extension, bit for bit.
        let d = m(0.0, 0.5, GltfSpecular::default(), None);
        let none = GltfMaterial {
            specular: None,
            ..d
        };
        assert_eq!(
            from_gltf_material(&d).unwrap(),
            from_gltf_material(&none).unwrap()
        );
        // Out of range: named.
        for bad in [
            spec(1.5, Vec3::ONE),
            spec(f32::NAN, Vec3::ONE),
            spec(1.0, Vec3::new(1.0, -0.1, 1.0)),
            spec(1.0, Vec3::new(1.0, f32::INFINITY, 1.0)),
        ] {
            let e = message(&m(0.0, 0.5, bad, None));
            assert!(e.contains("specular"), "{bad:?}: {e}");
        }
    }

    #[test]
    fn a_sheen_layers_the_opaque_part_and_spares_the_mirror_and_the_glass() {
        let sheen = |color, roughness| GltfSheen { color, roughness };
        let m = |metallic, roughness, s, transmission| GltfMaterial {
            sheen: Some(s),
            transmission,
            ..GltfMaterial::new(Vec3::splat(0.5), metallic, roughness)
        };
        let velvet = sheen(Vec3::new(0.9, 0.5, 0.1), 0.5);
        // A matte dielectric under a sheen is the glTF BRDF, not Lambert.
        let Ok(Brdf::GltfPbr(b)) = from_gltf_material(&m(0.0, 1.0, velvet, None)) else {
            panic!("a sheened matte dielectric")
        };
        assert_eq!(b.sheen(), (velvet.color, 0.5));
        // A black sheen is none: the shortcut again, bit for bit.
        let black = m(0.0, 1.0, sheen(Vec3::ZERO, 0.5), None);
        assert!(matches!(from_gltf_material(&black), Ok(Brdf::Lambert(_))));
        // A polished metal stays a mirror; glass takes no sheen, the
        // opaque part of a mix does.
        assert!(matches!(
            from_gltf_material(&m(1.0, 0.0, velvet, None)),
            Ok(Brdf::Mirror(_))
        ));
        let glass = from_gltf_material(&m(0.0, 0.5, velvet, Some(1.0))).unwrap();
        assert!(matches!(glass, Brdf::RoughDielectric(_)));
        let mix = gltf_lobes(&m(0.0, 0.5, velvet, Some(0.5))).unwrap();
        let Brdf::GltfPbr(opaque) = mix.surface else {
            panic!("the opaque part")
        };
        assert_eq!(opaque.sheen(), (velvet.color, 0.5));
        // Out of range: named.
        for (bad, name) in [
            (sheen(Vec3::new(1.0, 1.5, 1.0), 0.5), "sheenColorFactor"),
            (sheen(Vec3::new(-0.1, 1.0, 1.0), 0.5), "sheenColorFactor"),
            (sheen(Vec3::splat(f32::NAN), 0.5), "sheenColorFactor"),
            (sheen(Vec3::ONE, 1.5), "sheenRoughnessFactor"),
            (sheen(Vec3::ONE, f32::NAN), "sheenRoughnessFactor"),
        ] {
            let e = message(&m(0.0, 0.5, bad, None));
            assert!(e.contains(name), "{bad:?}: {e}");
        }
    }

    #[test]
    fn ior_zero_is_a_fresnel_of_one_and_nothing_transmits() {
        for m in [
            GltfMaterial {
                ior: Some(0.0),
                ..GltfMaterial::new(Vec3::splat(0.5), 0.0, 1.0)
            },
            GltfMaterial {
                ior: Some(0.0),
                ..glass(0.5)
            },
        ] {
            let Ok(Brdf::GltfPbr(b)) = from_gltf_material(&m) else {
                panic!("{m:?}: a white specular reflector")
            };
            assert_eq!(b.f0(), Vec3::ONE, "{m:?}");
        }
    }

    #[test]
    fn a_full_metal_transmits_nothing() {
        for roughness in [0.0, 0.5] {
            let metal = GltfMaterial {
                ior: Some(1.7),
                ..GltfMaterial::new(Vec3::new(0.9, 0.6, 0.3), 1.0, roughness)
            };
            let transmitting = GltfMaterial {
                transmission: Some(1.0),
                ..metal
            };
            let (a, b) = (
                from_gltf_material(&metal),
                from_gltf_material(&transmitting),
            );
            assert_eq!(a.unwrap(), b.unwrap(), "roughness {roughness}");
        }
    }

    #[test]
    fn full_transmission_is_glass() {
        let Ok(Brdf::Dielectric(d)) = from_gltf_material(&glass(0.0)) else {
            panic!("smooth glass is a dielectric")
        };
        assert_eq!(d.ior(), 1.5);
        assert_eq!(d.tint(), Vec3::new(0.9, 0.8, 0.7));
        assert!(d.thin(), "no volume extension: a thin wall");
        assert_eq!(d.attenuation(), Vec3::ZERO);
        // roughness 0.03: alpha 9e-4 < RoughDielectric::MIN_ALPHA, still smooth.
        assert!(matches!(
            from_gltf_material(&glass(0.03)),
            Ok(Brdf::Dielectric(_))
        ));
        let Ok(Brdf::RoughDielectric(r)) = from_gltf_material(&glass(0.5)) else {
            panic!("rough glass is a rough dielectric")
        };
        assert_eq!(r.alpha(), 0.25);
        let ior = GltfMaterial {
            ior: Some(1.33),
            ..glass(0.5)
        };
        let Ok(Brdf::RoughDielectric(r)) = from_gltf_material(&ior) else {
            panic!("rough water")
        };
        assert_eq!(r.ior(), 1.33);
        // An explicit 0 is opaque, like the absent extension.
        let none = GltfMaterial {
            transmission: Some(0.0),
            ..glass(1.0)
        };
        assert!(matches!(from_gltf_material(&none), Ok(Brdf::Lambert(_))));
    }

    #[test]
    fn volume_sets_thin_and_absorption() {
        let with = |v: GltfVolume| GltfMaterial {
            volume: Some(v),
            ..glass(0.0)
        };
        let thick = GltfVolume {
            thickness: 2.0,
            ..GltfVolume::default()
        };
        let Ok(Brdf::Dielectric(d)) = from_gltf_material(&with(thick)) else {
            panic!("a volume of glass")
        };
        assert!(!d.thin());
        assert_eq!(d.attenuation(), Vec3::ZERO, "no attenuationDistance");
        let absorbing = GltfVolume {
            attenuation_distance: 10.0,
            attenuation_color: Vec3::new(0.5, 1.0, 0.0),
            ..thick
        };
        let Ok(Brdf::Dielectric(d)) = from_gltf_material(&with(absorbing)) else {
            panic!("absorbing glass")
        };
        let s = d.attenuation();
        assert!((s.x - std::f32::consts::LN_2 / 10.0).abs() < 1e-7, "{s}");
        assert_eq!(s.y.to_bits(), 0.0f32.to_bits());
        assert_eq!(s.z, f32::MAX);
        // A thin wall has no interior: the attenuation has no effect.
        let thin = GltfVolume {
            thickness: 0.0,
            ..absorbing
        };
        let Ok(Brdf::Dielectric(d)) = from_gltf_material(&with(thin)) else {
            panic!("a thin wall")
        };
        assert!(d.thin());
        assert_eq!(d.attenuation(), Vec3::ZERO);
        // A tiny distance overflows to f32::MAX, not infinity.
        let tiny = GltfVolume {
            attenuation_distance: 1e-40,
            ..absorbing
        };
        let Ok(Brdf::Dielectric(d)) = from_gltf_material(&with(tiny)) else {
            panic!("dense glass")
        };
        assert_eq!(d.attenuation().x, f32::MAX);
    }

    #[test]
    fn partial_transmission_is_the_opaque_part_and_the_glass_part() {
        let part = |roughness, t| GltfMaterial {
            transmission: Some(t),
            ..glass(roughness)
        };
        // Smooth: a GltfPbr (its polished lobe) and smooth glass, both of
        // the material's tint and IOR.
        let lobes = gltf_lobes(&part(0.0, 0.3)).unwrap();
        let Brdf::GltfPbr(opaque) = lobes.surface else {
            panic!("the opaque part of a smooth dielectric is the glTF BRDF")
        };
        assert_eq!(opaque.f0(), Vec3::splat(0.04));
        let Some((0.3, Brdf::Dielectric(d))) = lobes.transmitted else {
            panic!("smooth glass of weight 0.3: {:?}", lobes.transmitted)
        };
        assert!(d.thin());
        // The parts are the opaque and the glass mappings themselves.
        let opaque_alone = GltfMaterial {
            transmission: None,
            ..part(0.5, 0.7)
        };
        let lobes = gltf_lobes(&part(0.5, 0.7)).unwrap();
        assert_eq!(lobes.surface, from_gltf_material(&opaque_alone).unwrap());
        assert_eq!(
            lobes.transmitted.map(|(_, g)| g),
            Some(from_gltf_material(&part(0.5, 1.0)).unwrap())
        );
        // Rough and matte: Lambert and rough glass.
        let lobes = gltf_lobes(&part(1.0, 0.5)).unwrap();
        assert!(matches!(lobes.surface, Brdf::Lambert(_)));
        assert!(matches!(
            lobes.transmitted,
            Some((0.5, Brdf::RoughDielectric(_)))
        ));
        // Whole glass and opaque stay one model.
        assert_eq!(gltf_lobes(&part(0.0, 1.0)).unwrap().transmitted, None);
        assert_eq!(gltf_lobes(&part(0.0, 0.0)).unwrap().transmitted, None);
        // A transmitting partial metal: glass takes (1 - m) t, the rest is
        // the opaque mapping of metallic m / (1 - (1 - m) t).
        let metal = |metallic, t, roughness| GltfMaterial {
            metallic,
            ..part(roughness, t)
        };
        let lobes = gltf_lobes(&metal(0.5, 0.5, 0.5)).unwrap();
        assert!(matches!(
            lobes.transmitted,
            Some((0.25, Brdf::RoughDielectric(_)))
        ));
        let Brdf::GltfPbr(rest) = lobes.surface else {
            panic!("a partial metal's rest is the glTF BRDF")
        };
        assert!(
            (rest.metallic() - 2.0 / 3.0).abs() < 1e-6,
            "{}",
            rest.metallic()
        );
        // Its factors map to it alone.
        assert_eq!(lobes.surface_factors.transmission, None);
        assert_eq!(
            from_gltf_material(&lobes.surface_factors).unwrap(),
            lobes.surface
        );
        // Whole transmission on a smooth partial metal: glass and a mirror.
        let lobes = gltf_lobes(&metal(0.25, 1.0, 0.0)).unwrap();
        assert!(matches!(
            lobes.transmitted,
            Some((0.75, Brdf::Dielectric(_)))
        ));
        assert!(
            matches!(lobes.surface, Brdf::Mirror(_)),
            "{:?}",
            lobes.surface
        );
        // A partly transmitting volume: its glass part refracts and absorbs.
        let volume = GltfMaterial {
            volume: Some(GltfVolume {
                thickness: 1.0,
                attenuation_distance: 2.0,
                attenuation_color: Vec3::splat(0.5),
            }),
            ..part(0.0, 0.5)
        };
        let Some((0.5, Brdf::Dielectric(d))) = gltf_lobes(&volume).unwrap().transmitted else {
            panic!("a refracting glass part")
        };
        assert!(!d.thin() && d.attenuation().x > 0.0);
    }

    #[test]
    fn bad_factors_are_refused_by_name_and_value() {
        let cases: [(GltfMaterial, &[&str]); 10] = [
            (
                GltfMaterial {
                    transmission: Some(1.5),
                    ..glass(0.0)
                },
                &["transmissionFactor", "1.5"],
            ),
            (
                GltfMaterial {
                    transmission: Some(f32::NAN),
                    ..glass(0.0)
                },
                &["transmissionFactor", "NaN"],
            ),
            (
                GltfMaterial {
                    transmission: Some(0.5),
                    ..glass(0.0)
                },
                &[
                    "partial transmission (a share 0.5 of glass) is a mix",
                    "gltf_lobes",
                ],
            ),
            (
                GltfMaterial {
                    metallic: 0.25,
                    ..glass(0.0)
                },
                &["a share 0.75 of glass", "gltf_lobes"],
            ),
            (
                GltfMaterial {
                    ior: Some(0.5),
                    ..glass(0.0)
                },
                &["`gltf ior`", "0.5"],
            ),
            (
                GltfMaterial {
                    ior: Some(4.5),
                    ..GltfMaterial::new(Vec3::ONE, 0.0, 1.0)
                },
                &["`gltf ior`", "4.5"],
            ),
            (
                GltfMaterial {
                    ior: Some(f32::NAN),
                    ..glass(0.0)
                },
                &["`gltf ior`", "NaN"],
            ),
            (
                GltfMaterial {
                    volume: Some(GltfVolume {
                        thickness: -1.0,
                        ..GltfVolume::default()
                    }),
                    ..glass(0.0)
                },
                &["thicknessFactor", "-1"],
            ),
            (
                GltfMaterial {
                    volume: Some(GltfVolume {
                        thickness: 1.0,
                        attenuation_distance: 0.0,
                        ..GltfVolume::default()
                    }),
                    ..glass(0.0)
                },
                &["attenuationDistance", "got 0"],
            ),
            (
                GltfMaterial {
                    volume: Some(GltfVolume {
                        thickness: 1.0,
                        attenuation_color: Vec3::new(1.0, 2.0, 1.0),
                        ..GltfVolume::default()
                    }),
                    ..glass(0.0)
                },
                &["attenuationColor", "2"],
            ),
        ];
        for (m, words) in cases {
            let msg = message(&m);
            for w in words {
                assert!(msg.contains(w), "{m:?}: {msg}");
            }
        }
        // Volume factors are checked on an opaque material too.
        let opaque = GltfMaterial {
            volume: Some(GltfVolume {
                attenuation_distance: f32::NAN,
                ..GltfVolume::default()
            }),
            ..GltfMaterial::new(Vec3::ONE, 0.0, 1.0)
        };
        assert!(message(&opaque).contains("attenuationDistance"));
    }
}
