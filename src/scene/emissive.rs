//! Emissive textures: a material's emitted radiance at a point is its
//! [`super::Emission::radiance`] (glTF's `emissiveFactor` times
//! `KHR_materials_emissive_strength`) times the texel there (sRGB-decoded
//! RGB, read through the texture's sampler at the mesh's transformed
//! texture coordinates, as base colour is: [`super::textured`]).
//!
//! The area light of a mesh whose material has one samples its points by
//! emitted power and knows its exact power ([`super::emission_map`]). It is
//! built when the mesh gets the texture coordinates the texture reads
//! ([`Scene::set_texcoords`]), or when a material whose meshes have them
//! gets its texture ([`Scene::set_emission_texture`]); until then the mesh
//! emits its factor, and [`Scene::validate`] refuses a scene left so.
//!
//! Every reader of emission goes through here or the light: the photon
//! tracer (the light's samples), the renderer and the path tracer at a hit
//! ([`Scene::emitted_radiance`], [`Scene::emission_texel`]) and in light
//! sampling ([`super::AreaLight::sample_point`] and its pdf).

use super::emission_map::EmissionMap;
use super::texture::{Encoding, Texture, TextureRef};
use super::{checks, Light, Scene};
use crate::error::{Error, Result};
use crate::raycast::Hit;
use glam::{Vec2, Vec3};
use std::sync::Arc;

impl Scene {
    /// Gives emissive material `material` an emissive texture (an index in
    /// [`Scene::textures`], its `TEXCOORD_n` set and transform); the area
    /// lights of its meshes that have that set are rebuilt from it.
    ///
    /// # Errors
    /// [`Error::InvalidScene`] for an unknown material or texture, a
    /// material that does not emit, or a light the texture makes unusable
    /// (its power overflows).
    pub fn set_emission_texture(&mut self, material: usize, texture: TextureRef) -> Result<()> {
        let Some(m) = self.materials.get(material) else {
            return Err(Error::InvalidScene(format!(
                "no material {material} to give an emissive texture"
            )));
        };
        if m.emission.is_none() {
            return Err(Error::InvalidScene(format!(
                "material `{}` does not emit: an emissive texture multiplies an emission",
                m.name
            )));
        }
        if texture.texture >= self.textures.len() {
            return Err(Error::InvalidScene(format!(
                "material `{}` reads emissive texture {}, which does not exist",
                m.name, texture.texture
            )));
        }
        if self.emission_textures.len() <= material {
            self.emission_textures.resize(material + 1, None);
        }
        self.emission_textures[material] = Some(texture);
        for mesh in 0..self.meshes.len() {
            if self.meshes[mesh].material == material {
                self.texture_area_light(mesh)?;
            }
        }
        Ok(())
    }

    /// The emissive texture of material `material`, when it has one.
    pub fn emission_texture(&self, material: usize) -> Option<&TextureRef> {
        self.emission_textures.get(material)?.as_ref()
    }

    /// What the emissive texture multiplies the emission by at a hit: the
    /// texel's RGB, or 1 without a texture (or off the scene's meshes).
    pub fn emission_texel(&self, hit: &Hit) -> Vec3 {
        let Some(r) = self.emission_texture(hit.material as usize) else {
            return Vec3::ONE;
        };
        match self.texcoord(hit, r) {
            Some(uv) => self.textures[r.texture]
                .sample(uv, Encoding::Srgb)
                .truncate(),
            None => Vec3::ONE,
        }
    }

    /// Radiance the surface at `hit` emits towards the unit direction `wo`
    /// (zero when its material does not emit).
    pub fn emitted_radiance(&self, hit: &Hit, wo: Vec3) -> Vec3 {
        let Some(e) = self
            .materials
            .get(hit.material as usize)
            .and_then(|m| m.emission)
        else {
            return Vec3::ZERO;
        };
        let l = e.radiance_at(hit.ng.dot(wo));
        if l == Vec3::ZERO {
            return l;
        }
        l * self.emission_texel(hit)
    }

    /// Rebuilds the area light of mesh `mesh` from its material's emissive
    /// texture, when it has one and the mesh has the coordinates it reads.
    /// A light whose covered texels are all black stays, with no power.
    pub(super) fn texture_area_light(&mut self, mesh: usize) -> Result<()> {
        let Some(m) = self.meshes.get(mesh) else {
            return Ok(());
        };
        let Some(r) = self.emission_texture(m.material).copied() else {
            return Ok(());
        };
        let Some(uvs) = m.texcoords.get(r.tex_coord).filter(|t| !t.is_empty()) else {
            return Ok(());
        };
        let per_triangle: Vec<[Vec2; 3]> = m
            .indices
            .iter()
            .map(|t| t.map(|i| r.transform.apply(uvs[i as usize])))
            .collect();
        let Some(slot) = self
            .lights
            .iter()
            .position(|l| matches!(l, Light::Area(a) if a.mesh == mesh))
        else {
            return Ok(());
        };
        let factor = self.materials[m.material]
            .emission
            .map_or(Vec3::ZERO, |e| e.radiance);
        let Light::Area(light) = self.lights[slot].clone() else {
            return Ok(());
        };
        let texture = self.shared_texture(r.texture);
        let name = &self.meshes[mesh].name;
        let light = match light
            .clone()
            .with_map(|triangles| EmissionMap::new(texture, factor, triangles, per_triangle))
        {
            Some(l) => l,
            None => {
                // Nothing it covers emits: a light of no power (it takes
                // no photons), and a warning.
                self.warnings.push(format!(
                    "emissive mesh `{name}`: every texel of its emissive texture that it covers is black: it emits nothing"
                ));
                light.dark()
            }
        };
        if let Some(why) = checks::power_problem(light.power()) {
            return Err(Error::InvalidScene(format!(
                "emissive mesh `{name}`: {why}"
            )));
        }
        self.lights[slot] = Light::Area(light);
        Ok(())
    }

    /// Texture `i` behind an `Arc`, copied once however many lights read it
    /// (a hundred primitives sharing a 4k emissive texture would otherwise
    /// hold a hundred copies of its 64 MB).
    fn shared_texture(&mut self, i: usize) -> Arc<Texture> {
        if self.shared_textures.len() <= i {
            self.shared_textures.resize(i + 1, None);
        }
        let texture = &self.textures[i];
        Arc::clone(self.shared_textures[i].get_or_insert_with(|| Arc::new(texture.clone())))
    }

    /// Checks that every mesh has the texture coordinates its material's
    /// emissive texture reads.
    pub(super) fn check_emission_texcoords(&self) -> Result<()> {
        for mesh in &self.meshes {
            let Some(r) = self.emission_texture(mesh.material) else {
                continue;
            };
            if mesh.texcoords.get(r.tex_coord).is_none_or(Vec::is_empty) {
                return Err(Error::InvalidScene(format!(
                    "mesh `{}` has no TEXCOORD_{}, which its material `{}`'s emissive texture reads",
                    mesh.name, r.tex_coord, self.materials[mesh.material].name
                )));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::Lambert;
    use crate::emitter::CosN;
    use crate::scene::texture::Sampler;
    use crate::scene::{Emission, Material};
    use std::f32::consts::PI;

    /// A unit square lamp (two triangles) of a material emitting 1, its
    /// mesh index, and a 2 x 1 texture: white, black.
    fn lamp() -> (Scene, usize, TextureRef) {
        let mut s = Scene::new();
        let m = s.add_material(Material {
            name: "lamp".into(),
            brdf: Lambert::new(Vec3::splat(0.5)).unwrap().into(),
            emission: Some(Emission::new(Vec3::ONE, CosN::new(0.0).unwrap())),
        });
        let p = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let positions = p.iter().map(|&[x, z]| Vec3::new(x, 0.0, z)).collect();
        s.add_mesh("lamp", positions, vec![[0, 2, 1], [0, 3, 2]], m)
            .unwrap();
        let texels = vec![[255, 255, 255, 255], [0, 0, 0, 255]];
        let t = s.add_texture(Texture::new(2, 1, texels, Sampler::default()).unwrap());
        let r = TextureRef {
            texture: t,
            tex_coord: 0,
            transform: Default::default(),
        };
        (s, m, r)
    }

    /// In code, the texture may come before or after the coordinates: the
    /// light is rebuilt either way, half its power gone with the black half
    /// (bilinear REPEAT over one tile: the mean of the texels).
    #[test]
    fn the_light_follows_the_texture_and_the_coordinates_in_either_order() {
        let uvs = vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];
        let (mut s, m, r) = lamp();
        assert!(s.validate().is_ok());
        s.set_emission_texture(m, r).unwrap();
        let e = s.validate().unwrap_err().to_string();
        assert!(
            e.contains("no TEXCOORD_0") && e.contains("emissive texture"),
            "{e}"
        );
        s.set_texcoords(0, 0, uvs.clone()).unwrap();
        let (mut t, m2, r2) = lamp();
        t.set_texcoords(0, 0, uvs).unwrap();
        t.set_emission_texture(m2, r2).unwrap();
        for scene in [&s, &t] {
            scene.validate().unwrap();
            let Light::Area(a) = &scene.lights()[0] else {
                panic!("an area light")
            };
            assert!(a.is_textured());
            assert!((a.power() - Vec3::splat(0.5 * PI)).abs().max_element() < 1e-5);
        }
        assert!(s.set_emission_texture(9, r).is_err());
        let bad = TextureRef { texture: 5, ..r };
        assert!(s.set_emission_texture(m, bad).is_err());
    }
}
