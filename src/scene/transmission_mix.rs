//! Materials that let part of the light through: glTF's
//! `0 < transmissionFactor < 1`, or transmission on a partial metal
//! ([`crate::brdf::gltf_lobes`]), the BSDF `(1 - w) opaque + w glass`.
//!
//! The engine decides per material where photons are stored (not on
//! mirrors and glass) and where camera paths pass through (mirrors and
//! glass). A mixed material is kept as two materials: the mesh's own, its
//! opaque part, and a glass part added after it. Where light *arrives*
//! nothing changes: photons are stored on the mixed surface with their
//! whole power (a photon records the flux that reaches a point, whatever
//! happens to it next) unless the opaque part is a mirror (a polished
//! partial metal that transmits: no photon is stored on it), and emission, textures and alpha masks are the
//! mesh's material's. Where light *scatters*, each event picks a part:
//! the glass part with probability `w`, else the opaque part, and then
//! scatters by that part alone with weight 1. The choice's probability is
//! the mixture's weight, so the expected scattering is the mixture's:
//! `w glass + (1 - w) opaque`. A camera path that picks the opaque part
//! reads the photon map there with the opaque part's BRDF, which counts
//! the stored photons once: the store did not depend on the choice.
//!
//! A refracting glass part makes the material's meshes the boundary of a
//! volume: what travels inside is absorbed by the glass part's attenuation
//! ([`Scene::interior_attenuation`]) at the hit that ends the segment,
//! whatever part then scatters there.
//!
//! Only mixed materials draw the choice's random number, so scenes
//! without one draw the same numbers as before and give the same photons
//! and images.

use super::Scene;
use crate::brdf::Brdf;
use crate::error::{Error, Result};

/// The part of a material that light passes through.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TransmissionMix {
    /// The glass part's share of the scattering, in (0, 1).
    pub weight: f32,
    /// The glass part, an index into [`Scene::materials`].
    pub glass: usize,
}

impl Scene {
    /// Makes material `material` (its opaque part: a mirror, or a model that
    /// stores photons) let the share `weight` of the light through by
    /// `glass`, a transmitting model, added as a material of its own
    /// (named after the material); a refracting
    /// `glass` makes the material's meshes the boundary of a volume, which
    /// absorbs what crosses it whatever part scatters. Returns the
    /// glass part's index.
    ///
    /// # Errors
    /// [`Error::InvalidScene`] for an unknown material, one that is itself
    /// glass or already mixed, a weight outside (0, 1), a `glass` that
    /// does not transmit, or a refracting (not thin) `glass` on a material
    /// with an alpha mask (a volume's mesh must be closed).
    pub fn set_transmission_mix(
        &mut self,
        material: usize,
        weight: f32,
        glass: Brdf,
    ) -> Result<usize> {
        let Some(m) = self.materials.get(material) else {
            return Err(Error::InvalidScene(format!(
                "no material {material} to mix with glass"
            )));
        };
        let name = m.name.clone();
        let refuse = |why: String| Err(Error::InvalidScene(format!("material `{name}`: {why}")));
        if m.brdf.is_transmissive() {
            return refuse("glass cannot take a transmitted part".into());
        }
        if self.transmission_mix(material as u32).is_some() {
            return refuse("it already has a transmitted part".into());
        }
        if !(weight > 0.0 && weight < 1.0) {
            return refuse(format!(
                "the transmitted share must be in (0, 1), got {weight}"
            ));
        }
        let thin = match glass {
            Brdf::Dielectric(g) => g.thin(),
            Brdf::RoughDielectric(g) => g.thin(),
            _ => {
                return refuse(format!(
                    "its transmitted part must be glass, got {}",
                    glass.kind()
                ))
            }
        };
        if !thin && self.alpha_mask(material).is_some() {
            return refuse(
                "a refracting transmitted part needs a closed mesh, and the material has an \
                 alpha mask"
                    .into(),
            );
        }
        let glass = self.add_material(super::Material {
            name: format!("{name} (transmitted part)"),
            brdf: glass,
            emission: None,
        });
        if self.transmission_mixes.len() <= material {
            self.transmission_mixes.resize(material + 1, None);
        }
        self.transmission_mixes[material] = Some(TransmissionMix { weight, glass });
        Ok(glass)
    }

    /// The transmitted part of material `material`, when it has one.
    #[inline]
    pub fn transmission_mix(&self, material: u32) -> Option<TransmissionMix> {
        *self.transmission_mixes.get(material as usize)?
    }

    /// The material that scatters at a hit on material `material`: for a
    /// mixed one, its glass part with probability its weight (`u()` in
    /// [0, 1) below it), else `material`; `u` is called only for a mixed
    /// material (module docs).
    #[inline]
    pub fn scattering_material(&self, material: u32, u: impl FnOnce() -> f32) -> u32 {
        match self.transmission_mix(material) {
            Some(mix) if u() < mix.weight => mix.glass as u32,
            _ => material,
        }
    }

    /// The absorption inside material `material`'s volume, when it bounds
    /// one that absorbs: its own model's, or its glass part's (the interior
    /// absorbs whatever part then scatters at the boundary).
    #[inline]
    pub fn interior_attenuation(&self, material: u32) -> Option<glam::Vec3> {
        let own = self.materials.get(material as usize)?.brdf;
        match self.transmission_mix(material) {
            Some(mix) => self.materials[mix.glass].brdf.interior_attenuation(),
            None => own.interior_attenuation(),
        }
    }

    /// Whether light may pass through material `material`: a mirror, glass
    /// or a mixed material (where caustic paths may start).
    pub fn may_scatter_specularly(&self, material: usize) -> bool {
        let specular = self
            .materials
            .get(material)
            .is_some_and(|m| m.brdf.is_specular());
        specular || self.transmission_mix(material as u32).is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::{Dielectric, Lambert};
    use crate::scene::Material;
    use glam::Vec3;

    fn scene() -> (Scene, usize) {
        let mut s = Scene::new();
        let m = s.add_material(Material {
            name: "frosted".into(),
            brdf: Lambert::new(Vec3::splat(0.5)).unwrap().into(),
            emission: None,
        });
        (s, m)
    }

    fn thin_glass(thin: bool) -> Brdf {
        Dielectric::new(1.5, Vec3::ONE, Vec3::ZERO, thin)
            .unwrap()
            .into()
    }

    #[test]
    fn the_glass_part_is_picked_with_its_weight() {
        let (mut s, m) = scene();
        let g = s.set_transmission_mix(m, 0.25, thin_glass(true)).unwrap();
        assert_eq!(s.materials[g].name, "frosted (transmitted part)");
        assert!(s.may_scatter_specularly(m) && s.may_scatter_specularly(g));
        let picked = |u: f32| s.scattering_material(m as u32, || u);
        assert_eq!(picked(0.0), g as u32);
        assert_eq!(picked(0.249), g as u32);
        assert_eq!(picked(0.25), m as u32);
        assert_eq!(picked(0.99), m as u32);
        // An unmixed material draws no number.
        let plain = s.scattering_material(g as u32, || unreachable!("no draw"));
        assert_eq!(plain, g as u32);
    }

    #[test]
    fn bad_mixes_are_refused_by_name() {
        let (mut s, m) = scene();
        let lambert: Brdf = Lambert::new(Vec3::ONE).unwrap().into();
        for (material, weight, glass, why) in [
            (9, 0.5, thin_glass(true), "no material 9"),
            (m, 0.0, thin_glass(true), "(0, 1), got 0"),
            (m, 1.0, thin_glass(true), "(0, 1), got 1"),
            (m, f32::NAN, thin_glass(true), "got NaN"),
            (m, 0.5, lambert, "must be glass"),
        ] {
            let e = s.set_transmission_mix(material, weight, glass).unwrap_err();
            assert!(e.to_string().contains(why), "{e}");
        }
        let g = s.set_transmission_mix(m, 0.5, thin_glass(true)).unwrap();
        let again = s
            .set_transmission_mix(m, 0.5, thin_glass(true))
            .unwrap_err();
        assert!(again.to_string().contains("already"), "{again}");
        let of_glass = s
            .set_transmission_mix(g, 0.5, thin_glass(true))
            .unwrap_err();
        assert!(of_glass.to_string().contains("glass cannot"), "{of_glass}");
        // A mirror may (a polished partial metal that transmits).
        let mirror = s.add_material(Material {
            name: "mirror".into(),
            brdf: crate::brdf::Mirror::new(Vec3::ONE).unwrap().into(),
            emission: None,
        });
        s.set_transmission_mix(mirror, 0.5, thin_glass(true))
            .unwrap();
    }
}
