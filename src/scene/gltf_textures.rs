//! A glTF material's textures: which are read ([`super::textured`]: base
//! colour and metallic-roughness, on opaque materials; normal textures,
//! [`super::normal_map`]), its alpha mask ([`super::alpha`]: `alphaMode:
//! MASK`, `alphaCutoff`, the alpha of `baseColorFactor` and
//! `baseColorTexture`), the images decoded once per texture, and the texture
//! coordinates of the meshes that use them (and of those an emissive texture
//! reads: [`super::gltf_emissive`]). What is not modelled is named in the
//! scene's warnings instead of being dropped silently: `alphaMode` BLEND
//! (traced as OPAQUE), and the base colour and metallic-roughness textures
//! of mirrors and glass.
//!
//! Images come from a `bufferView` (a GLB's usual form) or a `data:` URI.
//! Image files (`uri: "wood.png"`, `../textures/wood.png`) are read like
//! buffers: only inside the scene's asset root (see [`super::assets`]).

use super::alpha::AlphaMask;
use super::assets::AssetRoot;
use super::gltf_images::{decode, MAX_TEXELS};
use super::normal_map::NormalMap;
use super::texture::{Filter, Sampler, TexTransform, Texture, TextureRef, Wrap};
use super::textured::MaterialMaps;
use super::Scene;
use crate::brdf::{GltfClearcoat, GltfMaterial, GltfSheen};
use crate::error::{Error, Result};
use glam::{Vec2, Vec3};
use std::collections::HashMap;

/// Loads each texture once, the first time a material reads it.
pub(super) struct TextureLoader<'a> {
    doc: &'a gltf::Document,
    json: &'a gltf::json::Root,
    buffers: &'a [Vec<u8>],
    assets: Option<&'a AssetRoot>,
    /// glTF texture index -> scene texture index.
    loaded: HashMap<usize, usize>,
    /// Texels the scene's textures may still take.
    budget: u64,
    /// glTF textures without an image this loader reads, already warned of.
    sourceless: Vec<usize>,
}

fn wrap_of(w: gltf::texture::WrappingMode) -> Wrap {
    use gltf::texture::WrappingMode as W;
    match w {
        W::Repeat => Wrap::Repeat,
        W::ClampToEdge => Wrap::ClampToEdge,
        W::MirroredRepeat => Wrap::MirroredRepeat,
    }
}

fn sampler_of(s: &gltf::texture::Sampler) -> Sampler {
    Sampler {
        wrap_u: wrap_of(s.wrap_s()),
        wrap_v: wrap_of(s.wrap_t()),
        filter: match s.mag_filter() {
            Some(gltf::texture::MagFilter::Nearest) => Filter::Nearest,
            _ => Filter::Linear,
        },
    }
}

impl<'a> TextureLoader<'a> {
    pub(super) fn new(
        doc: &'a gltf::Document,
        buffers: &'a [Vec<u8>],
        assets: Option<&'a AssetRoot>,
    ) -> Self {
        TextureLoader {
            doc,
            json: doc.as_json(),
            buffers,
            assets,
            loaded: HashMap::new(),
            budget: MAX_TEXELS,
            sourceless: Vec::new(),
        }
    }

    /// The maps of material `m` (with factors `factors`), loading the
    /// textures it reads into `scene`; `None` when it reads none. What is
    /// ignored goes to the scene's warnings.
    pub(super) fn maps_of(
        &mut self,
        m: &gltf::Material,
        factors: GltfMaterial,
        specular: bool,
        scene: &mut Scene,
    ) -> Result<Option<MaterialMaps>> {
        let label = material_label(m);
        warn_unmodelled(m, &label, scene);
        let pbr = m.pbr_metallic_roughness();
        let ext = m.specular();
        // The textures that shape the BRDF: base colour, metallic-roughness,
        // specular strength, specular colour; and the clear coat's and the
        // sheen's, which the gltf crate does not parse (checked by
        // `check_json`).
        let mut shaping = [
            pbr.base_color_texture(),
            pbr.metallic_roughness_texture(),
            ext.as_ref().and_then(|s| s.specular_texture()),
            ext.as_ref().and_then(|s| s.specular_color_texture()),
        ];
        let mut layer_shaping =
            JSON_TEXTURES.map(|(ext, key)| m.extension_value(ext).and_then(|e| e.get(key)));
        let normal = m.normal_texture();
        let shapes = |a: &[Option<gltf::texture::Info>], b: &[Option<&serde_json::Value>]| {
            a.iter().any(Option::is_some) || b.iter().any(Option::is_some)
        };
        // A mirror or glass bends its normals, but scatters by its factors.
        if specular && shapes(&shaping, &layer_shaping) {
            scene.warnings.push(format!(
                "{label}: its base colour, metallic-roughness, specular, clear coat and \
                 sheen textures are not read (a mirror or glass scatters by its factors; \
                 only an alphaMode MASK reads the base colour texture's alpha)"
            ));
            shaping = [None, None, None, None];
            layer_shaping = [None; JSON_TEXTURES.len()];
        }
        if !shapes(&shaping, &layer_shaping) && normal.is_none() {
            return Ok(None);
        }
        let mut maps = MaterialMaps::new(factors);
        let [base, mr, strength, colour] = shaping;
        for (info, slot) in [
            (base, &mut maps.base_color),
            (mr, &mut maps.metallic_roughness),
            (strength, &mut maps.specular),
            (colour, &mut maps.specular_color),
        ] {
            if let Some(info) = info {
                *slot = self.texture_ref(&info, scene)?;
            }
        }
        let [coat_weight, coat_roughness, sheen_color, sheen_roughness] = layer_shaping;
        for (info, slot) in [
            (coat_weight, &mut maps.clearcoat),
            (coat_roughness, &mut maps.clearcoat_roughness),
            (sheen_color, &mut maps.sheen_color),
            (sheen_roughness, &mut maps.sheen_roughness),
        ] {
            if let Some(info) = info {
                *slot = self.json_texture_ref(info, scene)?;
            }
        }
        if let Some(n) = normal {
            maps.normal = self.normal_map(&n, scene)?;
        }
        let any = maps.refs().next().is_some();
        Ok(any.then_some(maps))
    }

    /// The scene texture of glTF texture `t`, loaded on first use; `None`
    /// (and a warning, once) when `t` names no image.
    fn scene_texture(&mut self, t: &gltf::Texture, scene: &mut Scene) -> Result<Option<usize>> {
        if let Some(&i) = self.loaded.get(&t.index()) {
            return Ok(Some(i));
        }
        let Some(image) = self.image_of(t) else {
            if !self.sourceless.contains(&t.index()) {
                self.sourceless.push(t.index());
                let label = super::gltf_checks::label("texture", t.index(), t.name());
                scene.warnings.push(format!(
                    "{label} has no `source` image: its image would come from an extension \
                     (KHR_texture_basisu) whose images are not decoded, so \
                     the materials that read it use their factors alone"
                ));
            }
            return Ok(None);
        };
        let texture = self.load(t, image)?;
        let i = scene.add_texture(texture);
        self.loaded.insert(t.index(), i);
        Ok(Some(i))
    }

    /// A `normalTexture`: not a `textureInfo` in the gltf crate, so its
    /// `KHR_texture_transform` is read from the extension's JSON (checked
    /// by [`check_json`]).
    fn normal_map(
        &mut self,
        n: &gltf::material::NormalTexture,
        scene: &mut Scene,
    ) -> Result<Option<NormalMap>> {
        let Some(texture) = self.scene_texture(&n.texture(), scene)? else {
            return Ok(None);
        };
        let (transform, set) = match n.extension_value(TRANSFORM) {
            Some(v) => transform_of_json(v)?,
            None => (TexTransform::default(), None),
        };
        Ok(Some(NormalMap {
            texture: TextureRef {
                texture,
                tex_coord: set.unwrap_or(n.tex_coord()) as usize,
                transform,
            },
            scale: n.scale(),
        }))
    }

    /// The alpha mask of material `m` when it is `alphaMode: MASK`: its
    /// `alphaCutoff` (default 0.5; checked by [`check_json`]), the alpha of
    /// `baseColorFactor`, and `baseColorTexture` (loaded here if the colour
    /// maps did not load it; a mirror's or glass's texture is read for its
    /// alpha alone).
    pub(super) fn mask_of(
        &mut self,
        m: &gltf::Material,
        scene: &mut Scene,
    ) -> Result<Option<AlphaMask>> {
        if m.alpha_mode() != gltf::material::AlphaMode::Mask {
            return Ok(None);
        }
        let pbr = m.pbr_metallic_roughness();
        let cutoff = m.alpha_cutoff().unwrap_or(AlphaMask::DEFAULT_CUTOFF);
        let mask = AlphaMask::new(cutoff, pbr.base_color_factor()[3]);
        let texture = pbr
            .base_color_texture()
            .map(|info| self.texture_ref(&info, scene));
        Ok(Some(match texture.transpose()?.flatten() {
            Some(t) => mask.with_texture(t),
            None => mask,
        }))
    }

    /// How `info` reads its texture; `None` when the texture names no image.
    pub(super) fn texture_ref(
        &mut self,
        info: &gltf::texture::Info,
        scene: &mut Scene,
    ) -> Result<Option<TextureRef>> {
        let Some(index) = self.scene_texture(&info.texture(), scene)? else {
            return Ok(None);
        };
        let (transform, tex_coord) = match info.texture_transform() {
            Some(x) => (
                TexTransform {
                    offset: Vec2::from(x.offset()),
                    rotation: x.rotation(),
                    scale: Vec2::from(x.scale()),
                },
                x.tex_coord().unwrap_or(info.tex_coord()),
            ),
            None => (TexTransform::default(), info.tex_coord()),
        };
        Ok(Some(TextureRef {
            texture: index,
            tex_coord: tex_coord as usize,
            transform,
        }))
    }

    /// How a `textureInfo` that the gltf crate does not parse (an
    /// extension's, checked by [`check_json`]) reads its texture; `None`
    /// when the texture names no image.
    fn json_texture_ref(
        &mut self,
        info: &serde_json::Value,
        scene: &mut Scene,
    ) -> Result<Option<TextureRef>> {
        let info = json_info(info)
            .map_err(|e| Error::InvalidScene(format!("a layer's texture is {e}")))?;
        let Some(t) = self.doc.textures().nth(info.index.value()) else {
            return Err(Error::InvalidScene(format!(
                "a texture info names texture {}, which does not exist",
                info.index.value()
            )));
        };
        let Some(texture) = self.scene_texture(&t, scene)? else {
            return Ok(None);
        };
        let x = info
            .extensions
            .as_ref()
            .and_then(|e| e.texture_transform.as_ref());
        let transform = x.map_or_else(TexTransform::default, |x| TexTransform {
            offset: Vec2::from(x.offset.0),
            rotation: x.rotation.0,
            scale: Vec2::from(x.scale.0),
        });
        let tex_coord = x.and_then(|x| x.tex_coord).unwrap_or(info.tex_coord);
        Ok(Some(TextureRef {
            texture,
            tex_coord: tex_coord as usize,
            transform,
        }))
    }

    /// The image glTF texture `t` reads: its `source`, or else the image
    /// `EXT_texture_webp` names (a file that requires the extension may
    /// leave `source` out; with both, `source` is the same picture in a
    /// core format). The gltf crate holds `u32::MAX` for a missing
    /// `source`, where its `source()` would panic.
    fn image_of(&self, t: &gltf::Texture) -> Option<usize> {
        let json = self.json.textures.get(t.index())?;
        if json.source.value() != NO_SOURCE {
            return Some(json.source.value());
        }
        let webp = json.extensions.as_ref()?.others.get(EXT_TEXTURE_WEBP)?;
        let i = usize::try_from(webp.get("source")?.as_u64()?).ok()?;
        (i < self.json.images.len()).then_some(i)
    }

    /// Decodes image `i`, the one glTF texture `t` reads
    /// ([`Self::image_of`]), with `t`'s sampler.
    fn load(&mut self, t: &gltf::Texture, i: usize) -> Result<Texture> {
        let image = &self.json.images[i];
        let what = super::gltf_checks::label("image", i, image.name.as_deref());
        let bytes = self.image_bytes(image, &what)?;
        let (w, h, texels) = decode(&what, &bytes, &mut self.budget)?;
        Texture::new(w, h, texels, sampler_of(&t.sampler()))
    }

    fn image_bytes(&self, image: &gltf::json::Image, what: &str) -> Result<Vec<u8>> {
        let missing = |why: &str| Error::InvalidScene(format!("{what}: {why}"));
        match (&image.buffer_view, &image.uri) {
            (Some(v), _) => {
                // Inside its buffer: checked by gltf_data::check_data.
                let view = self
                    .json
                    .buffer_views
                    .get(v.value())
                    .ok_or_else(|| missing("its bufferView is missing"))?;
                let data = self
                    .buffers
                    .get(view.buffer.value())
                    .ok_or_else(|| missing("its bufferView's buffer is missing"))?;
                let start = view.byte_offset.map_or(0, |o| o.0 as usize);
                data.get(start..start.saturating_add(view.byte_length.0 as usize))
                    .map(<[u8]>::to_vec)
                    .ok_or_else(|| missing("past its buffer's end"))
            }
            (None, Some(uri)) => super::assets::read_resource(
                what,
                uri,
                super::buffers::MAX_BUFFER_BYTES,
                self.assets,
            ),
            (None, None) => Err(missing("neither a bufferView nor a uri")),
        }
    }
}

/// The extension whose image a texture may read instead of its `source`.
const EXT_TEXTURE_WEBP: &str = "EXT_texture_webp";

/// The gltf crate's index for a texture's missing `source`.
const NO_SOURCE: usize = u32::MAX as usize;

pub(super) fn material_label(m: &gltf::Material) -> String {
    match m.index() {
        Some(i) => super::gltf_checks::label("material", i, m.name()),
        None => "the default material".to_string(),
    }
}

/// Warns of the parts of `m` the loader reads but does not model.
fn warn_unmodelled(m: &gltf::Material, label: &str, scene: &mut Scene) {
    let mut ignored = Vec::new();
    if m.alpha_mode() == gltf::material::AlphaMode::Blend {
        // MASK is modelled (`TextureLoader::mask_of`); BLEND's partial
        // coverage is not (docs/scenes.md).
        ignored.push("alphaMode BLEND (it is traced as OPAQUE: alpha is ignored)");
    }
    for what in ignored {
        scene
            .warnings
            .push(format!("{label}: {what} is not modelled"));
    }
    // The extensions the loader reads are parsed by the gltf crate, but the
    // clear coat and the sheen, read from their JSON; any other (unlit,
    // iridescence, ...) is ignored, and said so.
    for (name, value) in m.extensions().into_iter().flatten() {
        if name != CLEARCOAT && name != SHEEN {
            scene.warnings.push(format!(
                "{label}: its extension {name} is not modelled (ignored)"
            ));
            continue;
        }
        if name == CLEARCOAT && value.get("clearcoatNormalTexture").is_some() {
            scene.warnings.push(format!(
                "{label}: its {CLEARCOAT} clearcoatNormalTexture is not read (the coat \
                 takes the surface's shading normal)"
            ));
        }
    }
}

/// The clear coat extension, which the gltf crate does not parse.
const CLEARCOAT: &str = "KHR_materials_clearcoat";

/// The sheen extension, which the gltf crate does not parse.
const SHEEN: &str = "KHR_materials_sheen";

/// The textures read from the JSON of extensions the gltf crate does not
/// parse, as (extension, key): the clear coat's weight and roughness, the
/// sheen's colour and roughness.
const JSON_TEXTURES: [(&str, &str); 4] = [
    (CLEARCOAT, "clearcoatTexture"),
    (CLEARCOAT, "clearcoatRoughnessTexture"),
    (SHEEN, "sheenColorTexture"),
    (SHEEN, "sheenRoughnessTexture"),
];

/// A `textureInfo` of an extension the gltf crate does not parse; the
/// error says why not, for its caller to name what it read.
fn json_info(v: &serde_json::Value) -> std::result::Result<gltf::json::texture::Info, String> {
    serde_json::from_value(v.clone()).map_err(|e| format!("not a texture info ({e})"))
}

/// The factors of material `m`'s `KHR_materials_clearcoat` (read from its
/// JSON; ranges are checked by the mapping); `None` without it.
///
/// # Errors
/// A message naming the property when the extension is not an object or a
/// factor is not a number.
pub(super) fn clearcoat_of(
    m: &gltf::Material,
) -> std::result::Result<Option<GltfClearcoat>, String> {
    let Some(v) = extension_object(m, CLEARCOAT)? else {
        return Ok(None);
    };
    Ok(Some(GltfClearcoat {
        factor: json_number(v, CLEARCOAT, "clearcoatFactor")?,
        roughness: json_number(v, CLEARCOAT, "clearcoatRoughnessFactor")?,
    }))
}

/// The factors of material `m`'s `KHR_materials_sheen` (read from its
/// JSON; ranges are checked by the mapping); `None` without it.
///
/// # Errors
/// A message naming the property when the extension is not an object,
/// `sheenColorFactor` is not three numbers or `sheenRoughnessFactor` is not
/// a number.
pub(super) fn sheen_of(m: &gltf::Material) -> std::result::Result<Option<GltfSheen>, String> {
    let Some(v) = extension_object(m, SHEEN)? else {
        return Ok(None);
    };
    let color = match v.get("sheenColorFactor") {
        None => Vec3::ZERO,
        Some(x) => {
            rgb_of(x).ok_or_else(|| format!("{SHEEN} sheenColorFactor is not three numbers"))?
        }
    };
    Ok(Some(GltfSheen {
        color,
        roughness: json_number(v, SHEEN, "sheenRoughnessFactor")?,
    }))
}

/// Material `m`'s extension `ext` as a JSON object; `None` without it.
fn extension_object<'a>(
    m: &'a gltf::Material,
    ext: &str,
) -> std::result::Result<Option<&'a serde_json::Value>, String> {
    match m.extension_value(ext) {
        Some(v) if !v.is_object() => Err(format!("{ext} is not a JSON object")),
        v => Ok(v),
    }
}

/// The number `key` of extension `ext`'s object `v`, 0 when absent.
fn json_number(v: &serde_json::Value, ext: &str, key: &str) -> std::result::Result<f32, String> {
    match v.get(key) {
        None => Ok(0.0),
        Some(x) => x
            .as_f64()
            .map(|x| x as f32)
            .ok_or_else(|| format!("{ext} {key} is not a number")),
    }
}

/// A JSON array of three numbers as RGB.
fn rgb_of(v: &serde_json::Value) -> Option<Vec3> {
    match v.as_array()?.as_slice() {
        [r, g, b] => Some(Vec3::new(
            r.as_f64()? as f32,
            g.as_f64()? as f32,
            b.as_f64()? as f32,
        )),
        _ => None,
    }
}

/// Reads the texture coordinates the mesh's material needs, from primitive
/// `prim`, into mesh `mesh` of `scene`.
pub(super) fn load_texcoords(
    scene: &mut Scene,
    mesh: usize,
    prim: &gltf::Primitive,
    buffers: &[Vec<u8>],
    label: &str,
) -> Result<()> {
    let material = scene.meshes[mesh].material;
    let maps = scene.material_maps(material);
    let emissive = scene.emission_texture(material);
    let mask = scene.alpha_mask(material).and_then(|m| m.texture.as_ref());
    let mut sets: Vec<usize> = maps
        .into_iter()
        .flat_map(|m| m.refs())
        .chain(emissive)
        .chain(mask)
        .map(|r| r.tex_coord)
        .collect();
    sets.sort_unstable();
    sets.dedup();
    for set in sets {
        let Ok(set_u32) = u32::try_from(set) else {
            continue;
        };
        let Some(uvs) = prim.get(&gltf::mesh::Semantic::TexCoords(set_u32)) else {
            return Err(Error::InvalidScene(format!(
                "{label} has no TEXCOORD_{set}, which its material's textures read"
            )));
        };
        let uvs = super::gltf_quantized::read_f32_vectors::<2>(&uvs, buffers)?;
        let uvs: Vec<Vec2> = uvs.into_iter().map(Vec2::from).collect();
        scene.set_texcoords(mesh, set, uvs)?;
    }
    Ok(())
}

/// Gives mesh `mesh` of `scene` the tangents its material's normal texture
/// needs: primitive `prim`'s `TANGENT`s in world space `world` (the
/// handedness flips with a mirroring transform, as the bitangent must
/// follow the mirrored surface), else MikkTSpace's (always for a skinned
/// mesh, `world` `None`: its posed vertices give them).
pub(super) fn load_tangents(
    scene: &mut Scene,
    mesh: usize,
    prim: &gltf::Primitive,
    buffers: &[Vec<u8>],
    world: Option<&glam::Mat4>,
) -> Result<()> {
    let material = scene.meshes[mesh].material;
    let Some(map) = scene.material_maps(material).and_then(|m| m.normal) else {
        return Ok(());
    };
    let file_tangents = world.and_then(|w| Some((w, prim.get(&gltf::mesh::Semantic::Tangents)?)));
    let Some((world, accessor)) = file_tangents else {
        // A valid file may have texture coordinates that give no tangent
        // (all equal): it loads, shaded with its unbent normals.
        if let Err(e) = scene.generate_tangents(mesh, map.texture.tex_coord) {
            scene
                .warnings
                .push(format!("{e}; its normal texture is not applied"));
        }
        return Ok(());
    };
    let linear = glam::Mat3::from_mat4(*world);
    let sign = linear.determinant().signum();
    let tangents = super::gltf_quantized::read_f32_vectors::<4>(&accessor, buffers)?
        .into_iter()
        .map(|[x, y, z, w]| (linear * glam::Vec3::new(x, y, z)).extend(w * sign))
        .collect();
    scene.set_vertex_tangents(mesh, tangents)
}

/// The most texture coordinate sets a material may name (`TEXCOORD_0` to
/// `TEXCOORD_31`): a larger `texCoord` is refused rather than allocated.
const MAX_TEXCOORD_SETS: u32 = 32;

/// Checks the JSON that texture reading touches, before any of the gltf
/// crate's accessors (which index and unwrap) is called: texture, image and
/// sampler indices, enumerations, image sources, transforms.
pub(super) fn check_json(root: &gltf::json::Root) -> Result<()> {
    use gltf::json::validation::Checked;
    let bad = |m: String| Err(Error::InvalidScene(m));
    let label = super::gltf_checks::label;
    for (i, m) in root.materials.iter().enumerate() {
        let name = label("material", i, m.name.as_deref());
        if !matches!(m.alpha_mode, Checked::Valid(_)) {
            return bad(format!("{name} has an unknown alphaMode"));
        }
        // The schema's minimum; checked whatever the mode (a JSON number too
        // large for an f32 reads as infinity).
        if let Some(c) = m.alpha_cutoff.map(|c| c.0) {
            if !(c.is_finite() && c >= 0.0) {
                return bad(format!(
                    "{name} has the alphaCutoff {c}: it must be a finite number >= 0"
                ));
            }
        }
        let pbr = &m.pbr_metallic_roughness;
        let specular = m.extensions.as_ref().and_then(|e| e.specular.as_ref());
        let others = m.extensions.as_ref().map(|e| &e.others);
        for (ext, key) in JSON_TEXTURES {
            if let Some(v) = others.and_then(|o| o.get(ext)).and_then(|e| e.get(key)) {
                let info = json_info(v)
                    .map_err(|e| Error::InvalidScene(format!("{name}: its {ext} {key} is {e}")))?;
                check_info(root, &name, &info)?;
            }
        }
        for info in [
            &pbr.base_color_texture,
            &pbr.metallic_roughness_texture,
            &m.emissive_texture,
        ]
        .into_iter()
        .chain(specular.map(|s| &s.specular_texture))
        .chain(specular.map(|s| &s.specular_color_texture))
        .flatten()
        {
            check_info(root, &name, info)?;
        }
        if let Some(n) = &m.normal_texture {
            check_normal_texture(root, &name, n)?;
        }
        if let Some(o) = &m.occlusion_texture {
            check_index(&name, "texture", o.index.value(), root.textures.len())?;
        }
    }
    for (i, t) in root.textures.iter().enumerate() {
        let name = label("texture", i, t.name.as_deref());
        if t.source.value() != NO_SOURCE {
            check_index(&name, "image", t.source.value(), root.images.len())?;
        }
        let webp = t
            .extensions
            .as_ref()
            .and_then(|e| e.others.get(EXT_TEXTURE_WEBP));
        if let Some(source) = webp.and_then(|w| w.get("source")) {
            let i = source.as_u64().and_then(|i| usize::try_from(i).ok());
            let i = i.ok_or_else(|| {
                Error::InvalidScene(format!(
                    "{name}: {EXT_TEXTURE_WEBP} `source` is not an index"
                ))
            })?;
            check_index(&name, "image", i, root.images.len())?;
        }
        if let Some(s) = t.sampler {
            check_index(&name, "sampler", s.value(), root.samplers.len())?;
        }
    }
    for (i, s) in root.samplers.iter().enumerate() {
        let name = label("sampler", i, s.name.as_deref());
        let valid = matches!(s.wrap_s, Checked::Valid(_))
            && matches!(s.wrap_t, Checked::Valid(_))
            && s.mag_filter.is_none_or(|f| matches!(f, Checked::Valid(_)))
            && s.min_filter.is_none_or(|f| matches!(f, Checked::Valid(_)));
        if !valid {
            return bad(format!("{name} has an unknown wrap mode or filter"));
        }
    }
    for (i, im) in root.images.iter().enumerate() {
        let name = label("image", i, im.name.as_deref());
        match (&im.buffer_view, &im.uri) {
            (Some(v), None) => {
                check_index(&name, "bufferView", v.value(), root.buffer_views.len())?;
                if im.mime_type.is_none() {
                    return bad(format!("{name} has a bufferView but no mimeType"));
                }
            }
            (None, Some(_)) => {}
            _ => return bad(format!("{name} needs exactly one of uri and bufferView")),
        }
    }
    Ok(())
}

/// The extension a `normalTexture`'s transform is read from.
const TRANSFORM: &str = "KHR_texture_transform";

fn check_normal_texture(
    root: &gltf::json::Root,
    name: &str,
    n: &gltf::json::material::NormalTexture,
) -> Result<()> {
    check_index(name, "texture", n.index.value(), root.textures.len())?;
    let transform = n.extensions.as_ref().and_then(|e| e.others.get(TRANSFORM));
    let set = match transform {
        Some(v) => {
            transform_of_json(v)
                .map_err(|e| Error::InvalidScene(format!("{name}'s normalTexture: {e}")))?
                .1
        }
        None => None,
    };
    let set = set.unwrap_or(n.tex_coord);
    if set >= MAX_TEXCOORD_SETS {
        return Err(Error::InvalidScene(format!(
            "{name} reads TEXCOORD_{set}; at most {MAX_TEXCOORD_SETS} sets are read"
        )));
    }
    if !n.scale.is_finite() {
        return Err(Error::InvalidScene(format!(
            "{name} has a normalTexture scale that is not finite"
        )));
    }
    Ok(())
}

/// A `KHR_texture_transform` object as JSON: the transform, and the
/// `texCoord` it overrides (if any).
fn transform_of_json(v: &serde_json::Value) -> Result<(TexTransform, Option<u32>)> {
    let bad = |what: &str| Error::InvalidScene(format!("a KHR_texture_transform has {what}"));
    let number = |x: &serde_json::Value| x.as_f64().map(|f| f as f32).filter(|f| f.is_finite());
    let pair = |key: &str, default: Vec2| -> Result<Vec2> {
        match v.get(key) {
            None => Ok(default),
            Some(serde_json::Value::Array(a)) if a.len() == 2 => {
                match (number(&a[0]), number(&a[1])) {
                    (Some(x), Some(y)) => Ok(Vec2::new(x, y)),
                    _ => Err(bad(&format!("a {key} that is not two finite numbers"))),
                }
            }
            Some(_) => Err(bad(&format!("a {key} that is not two finite numbers"))),
        }
    };
    if !v.is_object() {
        return Err(bad("a value that is not an object"));
    }
    let rotation = match v.get("rotation") {
        None => 0.0,
        Some(r) => number(r).ok_or_else(|| bad("a rotation that is not a finite number"))?,
    };
    let set = match v.get("texCoord") {
        None => None,
        Some(t) => Some(
            t.as_u64()
                .and_then(|t| u32::try_from(t).ok())
                .ok_or_else(|| bad("a texCoord that is not a small non-negative integer"))?,
        ),
    };
    let transform = TexTransform {
        offset: pair("offset", Vec2::ZERO)?,
        rotation,
        scale: pair("scale", Vec2::ONE)?,
    };
    Ok((transform, set))
}

fn check_index(name: &str, kind: &str, i: usize, len: usize) -> Result<()> {
    if i < len {
        return Ok(());
    }
    Err(Error::InvalidScene(format!(
        "{name} refers to {kind} {i}, but there are only {len}"
    )))
}

fn check_info(root: &gltf::json::Root, name: &str, info: &gltf::json::texture::Info) -> Result<()> {
    check_index(name, "texture", info.index.value(), root.textures.len())?;
    let transform = info
        .extensions
        .as_ref()
        .and_then(|e| e.texture_transform.as_ref());
    let sets = [Some(info.tex_coord), transform.and_then(|t| t.tex_coord)];
    if let Some(set) = sets.into_iter().flatten().find(|&s| s >= MAX_TEXCOORD_SETS) {
        return Err(Error::InvalidScene(format!(
            "{name} reads TEXCOORD_{set}; at most {MAX_TEXCOORD_SETS} sets are read"
        )));
    }
    if let Some(t) = transform {
        let numbers = [
            t.offset.0[0],
            t.offset.0[1],
            t.rotation.0,
            t.scale.0[0],
            t.scale.0[1],
        ];
        if !numbers.iter().all(|v| v.is_finite()) {
            return Err(Error::InvalidScene(format!(
                "{name} has a KHR_texture_transform that is not finite"
            )));
        }
    }
    Ok(())
}
