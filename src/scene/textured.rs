//! Textured materials: a glTF metallic-roughness material whose base colour
//! and metallic-roughness factors are multiplied, at each surface point, by
//! texels ([`super::texture`]), read at the mesh's interpolated texture
//! coordinates.
//!
//! The material's own [`super::Material::brdf`] is the material at the
//! textures' mean texels: what the directionality analysis, the albedo
//! tables (survival probabilities) and the light's power estimates see.
//! Those only steer how many photons go where (any positive count keeps the
//! estimate unbiased, as the weights follow `power / m`). Every photon
//! bounce and every camera vertex scatters by the BRDF at its own point,
//! [`Scene::surface_brdf`].
//!
//! As glTF says (§3.9.2): base colour = `baseColorFactor * texel` (the
//! texel sRGB-decoded), metalness = `metallicFactor * texel.b`, roughness =
//! `roughnessFactor * texel.g` (linear); with `KHR_materials_specular`,
//! `specularFactor * texel.a` (linear) and `specularColorFactor * texel`
//! (sRGB-decoded); with `KHR_materials_clearcoat`, `clearcoatFactor *
//! texel.r` and `clearcoatRoughnessFactor * texel.g` (linear); with
//! `KHR_materials_sheen`, `sheenColorFactor * texel.rgb` (sRGB-decoded) and
//! `sheenRoughnessFactor * texel.a` (linear). The base
//! colour texture's alpha does not shade: with
//! `alphaMode: MASK` it cuts holes ([`super::alpha`]), where no ray stops.
//!
//! A point scatters in its material's class: the textures of a mirror or of
//! glass are not read (the tracer stores photons, and camera paths stop,
//! by material), and a texel that would make a metal polished enough to be
//! a mirror gives the sharpest lobe instead (roughness 0.0317).

use super::normal_map::NormalMap;
use super::texture::{Encoding, Texture, TextureRef};
use super::Scene;
use crate::brdf::{
    from_gltf_material, Brdf, GltfClearcoat, GltfMaterial, GltfSheen, GltfSpecular, Lambert,
};
use crate::error::{Error, Result};
use crate::raycast::Hit;
use glam::{Vec2, Vec3, Vec4};

/// The roughness below which the glTF mapping makes a metal a mirror is
/// `sqrt(GltfPbr::MIN_ALPHA)` = 0.03162...; a textured point is held just
/// above it.
const SMOOTHEST_TEXEL: f32 = 0.0317;

/// The textures of a glTF material, with the factors they multiply.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialMaps {
    /// The material's factors and extensions (as in the file).
    pub factors: GltfMaterial,
    /// `pbrMetallicRoughness.baseColorTexture` (sRGB).
    pub base_color: Option<TextureRef>,
    /// `pbrMetallicRoughness.metallicRoughnessTexture` (linear; roughness
    /// in green, metalness in blue).
    pub metallic_roughness: Option<TextureRef>,
    /// `normalTexture` (linear; [`super::normal_map`]).
    pub normal: Option<NormalMap>,
    /// `KHR_materials_specular.specularTexture` (linear; the strength in
    /// alpha).
    pub specular: Option<TextureRef>,
    /// `KHR_materials_specular.specularColorTexture` (sRGB).
    pub specular_color: Option<TextureRef>,
    /// `KHR_materials_clearcoat.clearcoatTexture` (linear; the weight in
    /// red).
    pub clearcoat: Option<TextureRef>,
    /// `KHR_materials_clearcoat.clearcoatRoughnessTexture` (linear; the
    /// roughness in green).
    pub clearcoat_roughness: Option<TextureRef>,
    /// `KHR_materials_sheen.sheenColorTexture` (sRGB).
    pub sheen_color: Option<TextureRef>,
    /// `KHR_materials_sheen.sheenRoughnessTexture` (linear; the roughness
    /// in alpha).
    pub sheen_roughness: Option<TextureRef>,
}

/// The decoded texels a point reads, `ONE` for a texture the material lacks.
struct Texels {
    base: Vec4,
    metallic_roughness: Vec4,
    specular: Vec4,
    specular_color: Vec4,
    clearcoat: Vec4,
    clearcoat_roughness: Vec4,
    sheen_color: Vec4,
    sheen_roughness: Vec4,
}

impl MaterialMaps {
    /// Factors `factors` with no texture yet.
    pub fn new(factors: GltfMaterial) -> Self {
        MaterialMaps {
            factors,
            base_color: None,
            metallic_roughness: None,
            normal: None,
            specular: None,
            specular_color: None,
            clearcoat: None,
            clearcoat_roughness: None,
            sheen_color: None,
            sheen_roughness: None,
        }
    }

    pub(super) fn refs(&self) -> impl Iterator<Item = &TextureRef> {
        let normal = self.normal.as_ref().map(|n| &n.texture);
        self.shaping().flatten().chain(normal)
    }

    /// The textures that change the BRDF (all but the normal texture), each
    /// with its encoding.
    fn shaping(&self) -> impl Iterator<Item = Option<&TextureRef>> {
        [
            self.base_color.as_ref(),
            self.metallic_roughness.as_ref(),
            self.specular.as_ref(),
            self.specular_color.as_ref(),
            self.clearcoat.as_ref(),
            self.clearcoat_roughness.as_ref(),
            self.sheen_color.as_ref(),
            self.sheen_roughness.as_ref(),
        ]
        .into_iter()
    }

    /// Whether any texture changes the BRDF.
    fn shapes_brdf(&self) -> bool {
        self.shaping().any(|r| r.is_some())
    }

    /// The texels `read` gives for each texture (`ONE` for a missing one).
    fn texels(&self, read: impl Fn(&TextureRef, Encoding) -> Vec4) -> Texels {
        let at = |r: &Option<TextureRef>, e| r.as_ref().map_or(Vec4::ONE, |r| read(r, e));
        Texels {
            base: at(&self.base_color, Encoding::Srgb),
            metallic_roughness: at(&self.metallic_roughness, Encoding::Linear),
            specular: at(&self.specular, Encoding::Linear),
            specular_color: at(&self.specular_color, Encoding::Srgb),
            clearcoat: at(&self.clearcoat, Encoding::Linear),
            clearcoat_roughness: at(&self.clearcoat_roughness, Encoding::Linear),
            sheen_color: at(&self.sheen_color, Encoding::Srgb),
            sheen_roughness: at(&self.sheen_roughness, Encoding::Linear),
        }
    }

    /// The factors at texels `t`.
    fn at(&self, t: &Texels) -> GltfMaterial {
        let f = &self.factors;
        GltfMaterial {
            base_color: f.base_color * t.base.truncate(),
            metallic: f.metallic * t.metallic_roughness.z,
            roughness: f.roughness * t.metallic_roughness.y,
            specular: f.specular.map(|s| GltfSpecular {
                factor: s.factor * t.specular.w,
                color: s.color * t.specular_color.truncate(),
            }),
            clearcoat: f.clearcoat.map(|c| GltfClearcoat {
                factor: c.factor * t.clearcoat.x,
                roughness: c.roughness * t.clearcoat_roughness.y,
            }),
            sheen: f.sheen.map(|s| GltfSheen {
                color: s.color * t.sheen_color.truncate(),
                roughness: s.roughness * t.sheen_roughness.w,
            }),
            ..*f
        }
    }
}

impl Scene {
    /// Adds a texture and returns its index in [`Scene::textures`].
    pub fn add_texture(&mut self, texture: Texture) -> usize {
        self.textures.push(texture);
        self.textures.len() - 1
    }

    /// The textures materials read.
    pub fn textures(&self) -> &[Texture] {
        &self.textures
    }

    /// Gives mesh `mesh` the texture coordinates `TEXCOORD_set`, one per
    /// vertex.
    ///
    /// # Errors
    /// [`Error::InvalidScene`] for an unknown mesh, a count that is not the
    /// mesh's vertex count, or a coordinate that is not finite.
    pub fn set_texcoords(&mut self, mesh: usize, set: usize, uvs: Vec<Vec2>) -> Result<()> {
        let what = ("texture coordinates", format!("TEXCOORD_{set} values"));
        let m = self.mesh_for_vertex_data(mesh, uvs.len(), what)?;
        if let Some(i) = uvs.iter().position(|uv| !uv.is_finite()) {
            return Err(Error::InvalidScene(format!(
                "mesh `{}` has a TEXCOORD_{set} value that is not finite (vertex {i})",
                m.name
            )));
        }
        if m.texcoords.len() <= set {
            m.texcoords.resize(set + 1, Vec::new());
        }
        m.texcoords[set] = uvs;
        // An emissive texture reading this set now shapes the mesh's light.
        self.texture_area_light(mesh)
    }

    /// Textures material `material`, and sets its [`super::Material::brdf`]
    /// to the material at the textures' mean texels (module docs).
    ///
    /// # Errors
    /// [`Error::InvalidScene`] for an unknown material or texture, or
    /// factors the glTF mapping refuses, naming the material.
    pub fn set_material_maps(&mut self, material: usize, maps: MaterialMaps) -> Result<()> {
        let Some(m) = self.materials.get(material) else {
            return Err(Error::InvalidScene(format!(
                "no material {material} to texture"
            )));
        };
        let name = m.name.clone();
        if let Some(r) = maps.refs().find(|r| r.texture >= self.textures.len()) {
            return Err(Error::InvalidScene(format!(
                "material `{name}` reads texture {}, which does not exist",
                r.texture
            )));
        }
        let at_mean = maps.at(&maps.texels(|r, e| self.textures[r.texture].mean(e)));
        // A normal texture alone leaves the BRDF (a mirror's or glass's too).
        if maps.shapes_brdf() {
            let brdf = from_gltf_material(&at_mean)
                .map_err(|e| Error::InvalidScene(format!("material `{name}`: {e}")))?;
            self.materials[material].brdf = brdf;
        }
        if self.material_maps.len() <= material {
            self.material_maps.resize(material + 1, None);
        }
        self.material_maps[material] = Some(maps);
        Ok(())
    }

    /// The textures of material `material`, when it has any.
    #[inline]
    pub fn material_maps(&self, material: usize) -> Option<&MaterialMaps> {
        self.material_maps.get(material)?.as_ref()
    }

    /// The BRDF at a hit: the material's, or for a textured material the
    /// one its textures give at the hit's texture coordinates. A hit the
    /// scene does not have gets the material's own BRDF (`Hit::check`
    /// refuses those before shading).
    ///
    /// The untextured case is inlined into the shading loops: returned from
    /// a call, the BRDF (52 bytes then, 68 now) was written by the callee and read back by
    /// the caller in wider loads, a store-forwarding stall at every hit that
    /// `perf annotate` put at 3 % of a render.
    #[inline]
    pub fn surface_brdf(&self, hit: &Hit) -> Option<Brdf> {
        let material = self.materials.get(hit.material as usize)?;
        match self.material_maps(hit.material as usize) {
            None => Some(material.brdf),
            Some(maps) => Some(self.textured_brdf(&material.brdf, maps, hit)),
        }
    }

    /// [`Self::surface_brdf`] of a material with textures `maps`, whose own
    /// BRDF is `own`.
    #[inline(never)]
    fn textured_brdf(&self, own: &Brdf, maps: &MaterialMaps, hit: &Hit) -> Brdf {
        // A point keeps its material's class: the tracer, the renderer and
        // the path tracer decide per material where photons are stored and
        // where paths pass through (module docs).
        if own.is_specular() {
            return *own;
        }
        let colour = self.vertex_color(hit);
        if !maps.shapes_brdf() && colour.is_none() {
            return *own;
        }
        let mut texels = maps.texels(|r, e| match self.texcoord(hit, r) {
            Some(uv) => self.textures[r.texture].sample(uv, e),
            None => Vec4::ONE,
        });
        // glTF's COLOR_0 multiplies the base colour texel.
        texels.base *= colour.unwrap_or(Vec3::ONE).extend(1.0);
        let base = texels.base;
        // Only the base colour texture (or COLOR_0) varies.
        let colour_only = maps.shaping().skip(1).all(|r| r.is_none());
        if colour_only {
            // Only the colour varies, and it does not change which model
            // the factors map to (module docs): the material's model with
            // the texel's colour.
            let colour = maps.factors.base_color * base.truncate();
            match own {
                Brdf::Lambert(_) => {
                    if let Ok(l) = Lambert::new(colour) {
                        return l.into();
                    }
                }
                Brdf::GltfPbr(g) => return g.with_base_color(colour).into(),
                _ => {}
            }
        }
        let mut at = maps.at(&texels);
        // A polished texel of a rough material stays a (sharp) lobe, not a
        // mirror.
        at.roughness = at.roughness.max(SMOOTHEST_TEXEL);
        // Texels are in [0, 1] and the factors were checked: the mapping
        // cannot refuse them, and would fall back to the mean if it did.
        from_gltf_material(&at).unwrap_or(*own)
    }

    /// The hit mesh's vertex colour at the hit, `None` when it has none.
    fn vertex_color(&self, hit: &Hit) -> Option<Vec3> {
        let mesh = self.meshes.get(hit.geom_id as usize)?;
        if mesh.colors.is_empty() {
            return None;
        }
        let [a, b, c] = *mesh.indices.get(hit.prim_id as usize)?;
        let (u, v) = (hit.u, hit.v);
        let colours = &mesh.colors;
        let colour =
            colours[a as usize] * (1.0 - u - v) + colours[b as usize] * u + colours[c as usize] * v;
        // Barycentrics at an edge may round a channel just past [0, 1].
        Some(colour.clamp(Vec3::ZERO, Vec3::ONE))
    }

    /// The transformed texture coordinates `r` reads at a hit, `None` when
    /// the mesh lacks its set.
    pub(super) fn texcoord(&self, hit: &Hit, r: &TextureRef) -> Option<Vec2> {
        let mesh = self.meshes.get(hit.geom_id as usize)?;
        let uvs = mesh.texcoords.get(r.tex_coord).filter(|t| !t.is_empty())?;
        let [a, b, c] = *mesh.indices.get(hit.prim_id as usize)?;
        let (u, v) = (hit.u, hit.v);
        let uv = uvs[a as usize] * (1.0 - u - v) + uvs[b as usize] * u + uvs[c as usize] * v;
        Some(r.transform.apply(uv))
    }

    /// Checks that every mesh has the texture coordinates its material's
    /// textures (and its alpha mask's) read.
    pub(super) fn check_texcoords(&self) -> Result<()> {
        for mesh in &self.meshes {
            let maps = self
                .material_maps(mesh.material)
                .into_iter()
                .flat_map(MaterialMaps::refs);
            let mask = self
                .alpha_mask(mesh.material)
                .and_then(|m| m.texture.as_ref());
            for r in maps.chain(mask) {
                if mesh.texcoords.get(r.tex_coord).is_none_or(Vec::is_empty) {
                    return Err(Error::InvalidScene(format!(
                        "mesh `{}` has no TEXCOORD_{}, which its material `{}` reads",
                        mesh.name, r.tex_coord, self.materials[mesh.material].name
                    )));
                }
            }
        }
        Ok(())
    }
}

/// The mean base colour a flat factor would need to stand in for `maps`
/// (for tests and reports).
pub fn flat_base_color(scene: &Scene, maps: &MaterialMaps) -> Vec3 {
    let mean = maps.base_color.map_or(Vec4::ONE, |r| {
        scene.textures[r.texture].mean(Encoding::Srgb)
    });
    maps.factors.base_color * mean.truncate()
}
