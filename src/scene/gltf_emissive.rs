//! A glTF material's `emissiveTexture` ([`super::emissive`]): read like the
//! base colour texture (its `texCoord`, sampler and `KHR_texture_transform`,
//! by [`super::gltf_textures`]), sRGB-encoded, multiplying `emissiveFactor`
//! (times `KHR_materials_emissive_strength`).
//!
//! A texture with a zero factor, or a factor with a texture black in every
//! texel, emits nothing: the material is not a light, and the scene's
//! warnings say why.

use super::gltf_textures::TextureLoader;
use super::texture::Encoding;
use super::Scene;
use crate::error::Result;

/// Reads material `m`'s emissive texture into scene material `id`.
pub(super) fn read_emissive(
    m: &gltf::Material,
    id: usize,
    loader: &mut TextureLoader,
    scene: &mut Scene,
) -> Result<()> {
    let Some(info) = m.emissive_texture() else {
        return Ok(());
    };
    let label = super::gltf_textures::material_label(m);
    if scene.materials[id].emission.is_none() {
        scene.warnings.push(format!(
            "{label}: its emissiveTexture multiplies an emissiveFactor of zero: it emits nothing"
        ));
        return Ok(());
    }
    let Some(r) = loader.texture_ref(&info, scene)? else {
        return Ok(());
    };
    let mean = scene.textures[r.texture].mean(Encoding::Srgb).truncate();
    if mean.max_element() <= 0.0 {
        scene.warnings.push(format!(
            "{label}: its emissiveTexture is black in every texel: it emits nothing"
        ));
        scene.materials[id].emission = None;
        return Ok(());
    }
    scene.set_emission_texture(id, r)
}
