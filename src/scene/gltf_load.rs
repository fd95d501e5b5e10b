//! glTF 2.0 (`.gltf` and `.glb`) to [`Scene`].
//!
//! - Every triangle primitive becomes a [`Mesh`](super::Mesh) in world space (node transforms applied).
//! - A material with a non-zero `emissiveFactor` (times `KHR_materials_emissive_strength`
//!   when present) makes its meshes area lights. Their `cos^n` exponent is the
//!   material's `extras.cosn` (a number >= 0; absent means 0, a diffuse emitter).
//!   A `doubleSided` one emits from both faces, a single-sided one from its
//!   front (the side its winding faces).
//! - A node whose world transform has a negative determinant (a mirror, a
//!   negative scale) reverses its triangles' winding, as glTF 2.0 §3.7.4 says:
//!   their front side, emission side and normals follow the mirrored geometry.
//! - Triangle lists, strips and fans are read (strips and fans become lists);
//!   points and lines are skipped with a [`Scene::warnings`] entry naming them.
//! - A primitive without a material gets the specification's default: a white
//!   metal of roughness 1.
//! - `KHR_lights_punctual` point, spot and directional lights are read,
//!   `color * intensity` taken as radiometric (candela as W/sr, lux as
//!   W/m^2, no photometric factor). A directional light shines along its
//!   node's -Z axis; its photon disc is fitted to the scene's bounds by
//!   [`Scene`] as meshes are added, not here (later nodes may add geometry).
//! - The first perspective camera found becomes [`Scene::camera`].
//! - Materials map to BRDFs by [`crate::brdf::gltf_map::gltf_lobes`]:
//!   metallic-roughness, with `KHR_materials_ior`, `KHR_materials_specular`
//!   (the dielectric's Fresnel colour and strength, with its textures),
//!   `KHR_materials_clearcoat` (a clear coat, with its weight and roughness
//!   textures), `KHR_materials_sheen` (a sheen under the coat, with its
//!   colour and roughness textures),
//!   `KHR_materials_transmission` (glass) and `KHR_materials_volume` (thin
//!   wall or refracting volume, absorption); partial transmission (or transmission on a partial
//!   metal) is its opaque part and a glass part
//!   ([`super::TransmissionMix`]); a value outside its range and a
//!   transmitting partial metal with a metallic-roughness texture are
//!   refused, naming the material.
//! - Base colour and metallic-roughness textures multiply their factors
//!   ([`super::gltf_textures`], [`super::textured`]); so does an
//!   `emissiveTexture` the emission, making an area light whose radiance
//!   varies over its surface, sampled by emitted power
//!   ([`super::gltf_emissive`], [`super::emissive`]); a `normalTexture`
//!   bends the shading normal ([`super::normal_map`]).
//! - `alphaMode: MASK` cuts holes where `baseColorFactor.a *
//!   baseColorTexture.a` is below `alphaCutoff` (default 0.5; a cut-off that
//!   is not finite or is negative is refused), which every ray passes
//!   through ([`super::alpha`]); a masked emitter with holes is refused.
//!   `alphaMode: BLEND` is traced as OPAQUE, with a [`Scene::warnings`]
//!   entry naming the material.
//! - `NORMAL` gives smooth shading normals ([`Scene::set_vertex_normals`]).
//! - `KHR_mesh_quantization`: POSITION, NORMAL and TEXCOORD_n may be 8- or
//!   16-bit integers ([`super::gltf_quantized`]): normalized ones are
//!   dequantized, others read as their values (the node's transform, or the
//!   texture transform, scales them).
//! - External files (buffers, images) are read from inside the asset root,
//!   [`LoadOptions::asset_root`] or by default the scene file's folder:
//!   `../buffers/x.bin` resolves against the scene's folder and may go
//!   anywhere inside the root, nothing outside it ([`super::assets`]).

use super::assets::AssetRoot;
use super::gltf_quantized::read_f32_vectors;
use super::gltf_skin::{JointMatrices, Skinning};
use super::{Camera, DirectionalLight, Emission, Light, Material, PointLight, Scene, SpotLight};
use crate::brdf::gltf_map::{
    from_gltf_material, gltf_lobes, GltfMaterial, GltfSpecular, GltfVolume,
};
use crate::brdf::Brdf;
use crate::emitter::CosN;
use crate::error::{Error, Result};
use glam::{Mat4, Vec3};
use gltf::mesh::{MorphTarget, Semantic};
use std::path::{Path, PathBuf};

/// How [`Scene::load_with`] reads a glTF file.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct LoadOptions {
    /// The folder the scene's external files (buffers, images) may be read
    /// from, anywhere inside it (`../buffers/x.bin`); it must hold the scene
    /// file's folder. `None`: the scene file's folder.
    pub asset_root: Option<PathBuf>,
}

impl LoadOptions {
    /// These options with `dir` as the asset root.
    pub fn with_asset_root(mut self, dir: impl Into<PathBuf>) -> Self {
        self.asset_root = Some(dir.into());
        self
    }
}

pub(super) fn load_path(path: &Path, options: &LoadOptions) -> Result<Scene> {
    let load_err = |e: Box<dyn std::error::Error + Send + Sync>| Error::Load {
        path: path.to_path_buf(),
        source: e,
    };
    // Before the scene is read: a scene outside its root is refused unread.
    let assets = AssetRoot::of_scene(path, options.asset_root.as_deref())?;
    // A scene file holds at most the buffers' 1 GiB limit, base64-encoded
    // (4/3 larger) in `data:` URIs, plus its JSON: 2 GiB is ample. Only a
    // regular file is read (a FIFO would block, `/dev/zero` never ends).
    const MAX_SCENE_FILE_BYTES: u64 = 2 << 30;
    let bytes = crate::input::read_regular_file(path, MAX_SCENE_FILE_BYTES)?;
    load_slice(&bytes, Some(&assets)).map_err(|e| match e {
        Error::Load { source, .. } => load_err(source),
        other => other,
    })
}

/// Loads from bytes; `assets` is where external files may be read (none
/// when `None`: a scene in memory).
///
/// Order matters: the JSON is validated ([`super::gltf_checks`]) before any of
/// the gltf crate's panicking accessors is called, buffers are loaded by
/// [`super::buffers`] (never outside the asset root), and byte ranges are checked
/// ([`super::gltf_data`]) and the node graph bounded ([`super::gltf_graph`])
/// before any accessor is read or any node expanded.
pub(super) fn load_slice(bytes: &[u8], assets: Option<&AssetRoot>) -> Result<Scene> {
    // load_path puts the scene file's path in these.
    let wrap = |e: gltf::Error| Error::Load {
        path: PathBuf::new(),
        source: Box::new(e),
    };
    check_glb_header(bytes).map_err(|message| Error::Load {
        path: PathBuf::new(),
        source: message.into(),
    })?;
    let gltf = match gltf::Gltf::from_slice_without_validation(bytes) {
        Ok(gltf) => gltf,
        // A valid file the crate's schema refuses (see gltf_relaxed) reads
        // once rewritten; any other keeps the crate's own error.
        Err(e) => super::gltf_relaxed::relaxed(bytes)
            .and_then(|b| gltf::Gltf::from_slice_without_validation(&b).ok())
            .ok_or_else(|| wrap(e))?,
    };
    super::gltf_checks::check_document(gltf.document.as_json())?;
    let mut buffers =
        super::buffers::load_buffers(gltf.document.as_json(), gltf.blob.clone(), assets)?;
    super::gltf_meshopt::decode_views(gltf.document.as_json(), &mut buffers)?;
    super::gltf_data::check_data(gltf.document.as_json(), &buffers)?;
    super::gltf_graph::check_graph(gltf.document.as_json())?;
    super::gltf_graph::check_forest(gltf.document.as_json())?;
    let doc = &gltf.document;

    let mut scene = Scene::new();
    for ext in super::gltf_checks::unread_extensions(doc.as_json()) {
        scene.warnings.push(format!(
            "the file uses the extension {ext}, which is not read: what it adds is ignored"
        ));
    }
    let mut material_ids = Vec::with_capacity(doc.materials().len());
    // The factors of each, for the maps that vertex colours need.
    let mut material_factors = Vec::with_capacity(doc.materials().len());
    let mut textures = super::gltf_textures::TextureLoader::new(doc, &buffers, assets);
    for m in doc.materials() {
        let Converted {
            material,
            factors,
            transmitted,
        } = convert_material(&m)?;
        let specular = material.brdf.is_specular();
        warn_unmodelled_layers(
            &m,
            (&material.brdf, transmitted.is_some(), &factors),
            &mut scene,
        );
        let id = scene.add_material(material);
        if let Some((weight, glass)) = transmitted {
            scene.set_transmission_mix(id, weight, glass)?;
        }
        material_factors.push(factors);
        if let Some(maps) = textures.maps_of(&m, factors, specular, &mut scene)? {
            scene.set_material_maps(id, maps)?;
        }
        super::gltf_emissive::read_emissive(&m, id, &mut textures, &mut scene)?;
        if let Some(mask) = textures.mask_of(&m, &mut scene)? {
            scene.set_alpha_mask(id, mask)?;
        }
        material_ids.push(id);
    }
    let mut default_material = None;

    let Some(root) = doc.default_scene().or_else(|| doc.scenes().next()) else {
        return Err(Error::InvalidScene("the glTF file has no scene".into()));
    };
    // Skinned meshes need their joints' world transforms, wherever in
    // the scene those nodes are.
    let worlds = world_transforms(doc, &root);
    let mut stack: Vec<(gltf::Node, Mat4)> = root.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    stack.reverse();
    // The graph is acyclic and its expansion bounded (gltf_checks::check_document).
    while let Some((node, parent)) = stack.pop() {
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        let instances = super::gltf_instancing::transforms(&node, doc, &buffers)?;
        load_node(
            &mut scene,
            &node,
            (&world, instances.as_deref()),
            (&buffers, &worlds),
            (&material_ids, &material_factors),
            &mut default_material,
        )
        .map_err(|e| match e {
            Error::InvalidScene(m) => Error::InvalidScene(format!(
                "{}: {m}",
                super::gltf_checks::label("node", node.index(), node.name())
            )),
            other => other,
        })?;
        let first_child = stack.len();
        stack.extend(node.children().map(|c| (c, world)));
        stack[first_child..].reverse();
    }
    // Nodes are visited depth-first in file order, so mesh (and Embree geometry) ids follow the file.
    // A file without a light loads: lights can be added before tracing,
    // where `PreparedScene::new` checks for one.
    scene.check_contents()?;
    Ok(scene)
}

/// Adds to `values` (a primitive's POSITION or NORMAL) the displacements
/// of its morph targets that `attribute` picks, times the default weights:
/// the node's `weights`, else the mesh's (glTF 2.0 §3.7.2.2). Animations,
/// which would change the weights, are not read.
fn morph<'a>(
    values: &mut [[f32; 3]],
    prim: &gltf::Primitive<'a>,
    node: &gltf::Node,
    buffers: &[Vec<u8>],
    attribute: fn(&MorphTarget<'a>) -> Option<gltf::Accessor<'a>>,
) -> Result<()> {
    let Some(weights) = node.weights().or(node.mesh().and_then(|m| m.weights())) else {
        return Ok(());
    };
    for (target, &w) in prim.morph_targets().zip(weights) {
        let Some(accessor) = attribute(&target).filter(|_| w != 0.0) else {
            continue;
        };
        let displacements = read_f32_vectors::<3>(&accessor, buffers)?;
        if displacements.len() != values.len() {
            return Err(Error::InvalidScene(format!(
                "a morph target has {} displacements for {} vertices",
                displacements.len(),
                values.len()
            )));
        }
        if !w.is_finite() {
            return Err(Error::InvalidScene(format!(
                "a morph target's weight {w} is not finite"
            )));
        }
        for (v, d) in values.iter_mut().zip(displacements) {
            for k in 0..3 {
                v[k] += w * d[k];
            }
        }
    }
    Ok(())
}

/// The world transform of every node of scene `root` (by node index;
/// `None` for a node outside it). The graph is a forest
/// (gltf_graph::check_forest).
fn world_transforms(doc: &gltf::Document, root: &gltf::Scene) -> Vec<Option<Mat4>> {
    let mut worlds = vec![None; doc.nodes().len()];
    let mut stack: Vec<(gltf::Node, Mat4)> = root.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    while let Some((node, parent)) = stack.pop() {
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        worlds[node.index()] = Some(world);
        stack.extend(node.children().map(|c| (c, world)));
    }
    worlds
}

/// Adds `message` to the scene's warnings unless it is there: a mesh that
/// several nodes instance warns once.
fn warn_once(scene: &mut Scene, message: String) {
    if !scene.warnings.contains(&message) {
        scene.warnings.push(message);
    }
}

/// One node's meshes, light and camera, in world space `world`; its mesh
/// once per instance when `instances` gives their transforms
/// (`EXT_mesh_gpu_instancing`).
fn load_node(
    scene: &mut Scene,
    node: &gltf::Node,
    (world, instances): (&Mat4, Option<&[Mat4]>),
    (buffers, worlds): (&[Vec<u8>], &[Option<Mat4>]),
    (material_ids, material_factors): (&[usize], &[GltfMaterial]),
    default_material: &mut Option<usize>,
) -> Result<()> {
    if !world.is_finite() {
        return Err(Error::InvalidScene(
            "its world transform is not finite".into(),
        ));
    }
    if let Some(mesh) = node.mesh() {
        if instances.is_some() && node.skin().is_some() {
            return Err(Error::InvalidScene(format!(
                "its skinned mesh has instances ({}): a skin ignores its node's transform, so \
                 they would coincide",
                super::gltf_instancing::EXT_MESH_GPU_INSTANCING
            )));
        }
        let data = (buffers, worlds);
        let materials = (material_ids, material_factors);
        // Times the identity, a matrix is itself, bit for bit.
        for (i, m) in instances.unwrap_or(&[Mat4::IDENTITY]).iter().enumerate() {
            let placed = *world * *m;
            if !placed.is_finite() {
                return Err(Error::InvalidScene(format!(
                    "its instance {i}'s world transform is not finite"
                )));
            }
            load_mesh(
                scene,
                node,
                &mesh,
                &placed,
                data,
                materials,
                default_material,
            )?;
        }
    }
    if let Some(light) = node.light() {
        scene.add_light(convert_light(&light, world)?)?;
    }
    if let Some(cam) = node.camera() {
        if let (gltf::camera::Projection::Perspective(p), None) = (cam.projection(), scene.camera) {
            // A sheared or scaled node: keep up orthogonal to forward.
            let forward = world.transform_vector3(-Vec3::Z).normalize();
            let up = world.transform_vector3(Vec3::Y);
            scene.set_camera(Camera {
                eye: world.transform_point3(Vec3::ZERO),
                forward,
                up: (up - forward * up.dot(forward)).normalize(),
                vfov_deg: p.yfov().to_degrees(),
            })?;
        }
    }
    Ok(())
}

/// Mesh `mesh` of node `node` (its primitives, morph targets and skin) in
/// world space `world`.
fn load_mesh(
    scene: &mut Scene,
    node: &gltf::Node,
    mesh: &gltf::Mesh,
    world: &Mat4,
    (buffers, worlds): (&[Vec<u8>], &[Option<Mat4>]),
    (material_ids, material_factors): (&[usize], &[GltfMaterial]),
    default_material: &mut Option<usize>,
) -> Result<()> {
    let mesh_label = super::gltf_checks::label("mesh", mesh.index(), mesh.name());
    // A skinned mesh is posed by its joints and ignores its node's
    // transform (glTF 2.0 §3.7.3.3).
    let skin = match node.skin() {
        Some(s) => Some(JointMatrices::of(&s, buffers, worlds)?),
        None => None,
    };
    for (pi, prim) in mesh.primitives().enumerate() {
        if !is_triangles(prim.mode()) {
            // Once, however many nodes or GPU instances place the mesh.
            warn_once(
                scene,
                format!(
                    "{mesh_label} primitive {pi} ({:?}) was skipped: only triangles are traced",
                    prim.mode()
                ),
            );
            continue;
        }
        let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d[..]));
        let Some(positions) = prim.get(&Semantic::Positions) else {
            return Err(Error::InvalidScene(format!(
                "{mesh_label} primitive {pi} has no POSITION attribute"
            )));
        };
        let skinning = match &skin {
            Some(joints) => {
                let s = Skinning::of(joints, &prim, buffers)?;
                if s.is_none() {
                    warn_once(
                        scene,
                        format!(
                            "{mesh_label} primitive {pi}: it has a skin but no JOINTS_0 \
                                 and WEIGHTS_0: it is placed by its node"
                        ),
                    );
                }
                s
            }
            None => None,
        };
        let mut positions = read_f32_vectors::<3>(&positions, buffers)?;
        morph(&mut positions, &prim, node, buffers, MorphTarget::positions)?;
        if let Some(s) = skinning.as_ref().filter(|s| s.len() != positions.len()) {
            return Err(Error::InvalidScene(format!(
                "{mesh_label} primitive {pi} has {} positions but {} joint weights",
                positions.len(),
                s.len()
            )));
        }
        let positions: Vec<Vec3> = positions
            .into_iter()
            .enumerate()
            .map(|(v, p)| match &skinning {
                Some(s) => s.point(v, Vec3::from(p)),
                None => world.transform_point3(Vec3::from(p)),
            })
            .collect();
        // glTF 2.0 §3.7.4: a negative determinant mirrors the node, which
        // reverses its triangles' winding (and so their front side).
        let mirrored = match &skinning {
            Some(s) => s.mirrors(),
            None => glam::Mat3::from_mat4(*world).determinant() < 0.0,
        };
        let flat: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None => (0..positions.len() as u32).collect(),
        };
        let mut indices = triangle_list(prim.mode(), &flat);
        if mirrored {
            indices.iter_mut().for_each(|t| t.swap(1, 2));
        }
        let (material, factors) = match prim.material().index() {
            Some(i) => (material_ids[i], material_factors[i]),
            None => match *default_material {
                Some(id) => (id, spec_default_factors()),
                None => {
                    let id = scene.add_material(spec_default_material()?);
                    *default_material = Some(id);
                    (id, spec_default_factors())
                }
            },
        };
        // NORMAL: shading normals, by the inverse transpose of the node's matrix.
        let normal_matrix = world.inverse().transpose();
        let normals = match prim.get(&Semantic::Normals) {
            Some(n) => {
                let mut n = read_f32_vectors::<3>(&n, buffers)?;
                morph(&mut n, &prim, node, buffers, MorphTarget::normals)?;
                Some(n)
            }
            None => None,
        };
        let normals: Option<Vec<Vec3>> = normals.map(|n| {
            n.into_iter()
                .enumerate()
                .map(|(i, v)| match &skinning {
                    Some(s) if i < s.len() => s.normal(i, Vec3::from(v)),
                    _ => normal_matrix.transform_vector3(Vec3::from(v)),
                })
                .collect()
        });
        let name = format!("{}#{pi}", mesh.name().unwrap_or("mesh"));
        let index = scene.add_mesh(name, positions, indices, material)?;
        if let Some(n) = normals {
            scene.set_vertex_normals(index, n)?;
        }
        let prim_label = format!("{mesh_label} primitive {pi}");
        super::gltf_textures::load_texcoords(scene, index, &prim, buffers, &prim_label)?;
        // A posed mesh's tangents are generated from its posed vertices.
        let tangent_space = skinning.is_none().then_some(world);
        super::gltf_textures::load_tangents(scene, index, &prim, buffers, tangent_space)?;
        load_colors(scene, index, &prim, buffers, factors)?;
    }
    Ok(())
}

/// Warns of the layers a material's model leaves out (`brdf/gltf_map.rs`):
/// `KHR_materials_specular` on its glass part, which keeps its IOR's exact
/// Fresnel term, and a clear coat or a sheen on glass or on a polished
/// metal (a mirror). `(brdf, partly, factors)`: the material's model,
/// whether it transmits partly, and the factors it was mapped from.
fn warn_unmodelled_layers(
    m: &gltf::Material,
    (brdf, partly, factors): (&Brdf, bool, &GltfMaterial),
    scene: &mut Scene,
) {
    let label = super::gltf_textures::material_label(m);
    let coated = factors.clearcoat.is_some_and(|c| c.factor > 0.0);
    let sheened = factors.sheen.is_some_and(|s| s.color.max_element() > 0.0);
    let layers = [
        (coated, "KHR_materials_clearcoat"),
        (sheened, "KHR_materials_sheen"),
    ];
    let present = layers.into_iter().filter(|&(on, _)| on).map(|(_, ext)| ext);
    if matches!(brdf, Brdf::Mirror(_)) {
        for ext in present.clone() {
            scene.warnings.push(format!(
                "{label}: {ext} is not modelled on a polished metal, which is traced as a \
                 mirror"
            ));
        }
    }
    let glass = partly || matches!(brdf, Brdf::Dielectric(_) | Brdf::RoughDielectric(_));
    if !glass {
        return;
    }
    let changes = m.specular().is_some_and(|s| {
        s.specular_factor() != 1.0
            || s.specular_color_factor() != [1.0; 3]
            || s.specular_texture().is_some()
            || s.specular_color_texture().is_some()
    });
    if changes {
        scene.warnings.push(format!(
            "{label}: KHR_materials_specular is not modelled on its transmitting (glass) part, \
             which reflects by its IOR's Fresnel term"
        ));
    }
    for ext in present {
        scene.warnings.push(format!(
            "{label}: {ext} is not modelled on its transmitting (glass) part"
        ));
    }
}

/// The factors of glTF 2.0's default material: white, metallic 1,
/// roughness 1.
fn spec_default_factors() -> GltfMaterial {
    GltfMaterial::new(Vec3::ONE, 1.0, 1.0)
}

/// Reads primitive `prim`'s `COLOR_0` (VEC3 or VEC4; alpha unused) into
/// mesh `mesh`, and gives its material (of glTF factors `factors`) maps
/// when it has none, so that its hits read the colours. Mirrors and glass
/// scatter by their factors: their vertex colours are a warning.
fn load_colors(
    scene: &mut Scene,
    mesh: usize,
    prim: &gltf::Primitive,
    buffers: &[Vec<u8>],
    factors: GltfMaterial,
) -> Result<()> {
    let Some(accessor) = prim.get(&Semantic::Colors(0)) else {
        return Ok(());
    };
    let material = scene.meshes[mesh].material;
    if scene.materials[material].brdf.is_specular() {
        let message = format!(
            "mesh `{}`: its vertex colours (COLOR_0) are not read: a mirror or glass scatters \
             by its factors",
            scene.meshes[mesh].name
        );
        scene.warnings.push(message);
        return Ok(());
    }
    let colors: Vec<Vec3> = match accessor.dimensions() {
        gltf::accessor::Dimensions::Vec4 => read_f32_vectors::<4>(&accessor, buffers)?
            .into_iter()
            .map(|[r, g, b, _]| Vec3::new(r, g, b))
            .collect(),
        _ => read_f32_vectors::<3>(&accessor, buffers)?
            .into_iter()
            .map(Vec3::from)
            .collect(),
    };
    scene.set_vertex_colors(mesh, colors)?;
    if scene.material_maps(material).is_none() {
        scene.set_material_maps(material, super::textured::MaterialMaps::new(factors))?;
    }
    Ok(())
}

/// glTF 2.0's default material (§3.9.6), for primitives without one: the
/// metallic-roughness defaults, a white metal of roughness 1.
fn spec_default_material() -> Result<Material> {
    let brdf = from_gltf_material(&spec_default_factors())
        .map_err(|e| Error::InvalidScene(format!("the default material: {e}")))?;
    Ok(Material {
        name: "default".into(),
        brdf,
        emission: None,
    })
}

/// A glTF material as the scene takes it.
struct Converted {
    material: Material,
    /// The factors its textures modulate: its opaque part's when it
    /// transmits partly.
    factors: GltfMaterial,
    /// Its transmitted part and that part's share, when it transmits partly.
    transmitted: Option<(f32, Brdf)>,
}

fn convert_material(m: &gltf::Material) -> Result<Converted> {
    let label = match m.index() {
        Some(i) => super::gltf_checks::label("material", i, m.name()),
        None => "the default material".to_string(),
    };
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, _] = pbr.base_color_factor();
    let input = GltfMaterial {
        base_color: Vec3::new(r, g, b),
        metallic: pbr.metallic_factor(),
        roughness: pbr.roughness_factor(),
        transmission: m.transmission().map(|t| t.transmission_factor()),
        ior: m.ior(),
        volume: m.volume().map(|v| GltfVolume {
            thickness: v.thickness_factor(),
            attenuation_distance: v.attenuation_distance(),
            attenuation_color: Vec3::from(v.attenuation_color()),
        }),
        specular: m.specular().map(|s| GltfSpecular {
            factor: s.specular_factor(),
            color: Vec3::from(s.specular_color_factor()),
        }),
        clearcoat: super::gltf_textures::clearcoat_of(m)
            .map_err(|e| Error::InvalidScene(format!("{label}: {e}")))?,
        sheen: super::gltf_textures::sheen_of(m)
            .map_err(|e| Error::InvalidScene(format!("{label}: {e}")))?,
    };
    let lobes = gltf_lobes(&input).map_err(|e| Error::InvalidScene(format!("{label}: {e}")))?;
    let brdf = lobes.surface;
    let strength = m.emissive_strength().unwrap_or(1.0);
    let radiance = Vec3::from(m.emissive_factor()) * strength;
    if !radiance.is_finite() || radiance.min_element() < 0.0 {
        return Err(Error::InvalidScene(format!(
            "{label} has an invalid emission {radiance}"
        )));
    }
    let emission = if radiance.max_element() > 0.0 {
        Some(Emission {
            radiance,
            profile: CosN::new(cosn_of(m)?)?,
            // Viewers and Blender's Cycles light both faces of a
            // double-sided emitter; a single-sided one emits from its front.
            two_sided: m.double_sided(),
        })
    } else {
        None
    };
    let material = Material {
        name: m.name().unwrap_or("unnamed").to_string(),
        brdf,
        emission,
    };
    // The glass part's share is one number per material: a texel's
    // metallic would change it, on a transmitting partial metal.
    let metal_texture = m.pbr_metallic_roughness().metallic_roughness_texture();
    if lobes.transmitted.is_some() && input.metallic > 0.0 && metal_texture.is_some() {
        return Err(Error::InvalidScene(format!(
            "{label}: a transmitting partial metal (metallicFactor {}) with a \
             metallicRoughnessTexture is not supported (its glass share would vary by texel)",
            input.metallic
        )));
    }
    // The textures of a partly transmitting material modulate its opaque
    // part: its factors are that part's.
    Ok(Converted {
        material,
        factors: lobes.surface_factors,
        transmitted: lobes.transmitted,
    })
}

/// `extras.cosn` of a material, 0 when absent.
fn cosn_of(m: &gltf::Material) -> Result<f32> {
    let Some(raw) = m.extras() else {
        return Ok(0.0);
    };
    let value: serde_json::Value = serde_json::from_str(raw.get())
        .map_err(|e| Error::param("cosn exponent", format!("extras are not valid JSON: {e}")))?;
    match value.get("cosn") {
        None => Ok(0.0),
        Some(serde_json::Value::Number(n)) => Ok(n.as_f64().unwrap_or(f64::NAN) as f32),
        Some(other) => Err(Error::param(
            "cosn exponent",
            format!(
                "material `{}` has extras.cosn = {other}, not a number",
                m.name().unwrap_or("?")
            ),
        )),
    }
}

fn convert_light(light: &gltf::khr_lights_punctual::Light, world: &Mat4) -> Result<Light> {
    use gltf::khr_lights_punctual::Kind;
    let intensity = Vec3::from(light.color()) * light.intensity();
    if !intensity.is_finite() || intensity.min_element() < 0.0 {
        return Err(Error::InvalidScene(format!(
            "light `{}` has an invalid intensity {intensity}",
            light.name().unwrap_or("?")
        )));
    }
    let position = world.transform_point3(Vec3::ZERO);
    match light.kind() {
        Kind::Point => Ok(Light::Point(PointLight {
            position,
            intensity,
        })),
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => {
            // Ranges were checked by gltf_checks::check_light: no silent clamp.
            let (inner, outer) = (inner_cone_angle, outer_cone_angle);
            Ok(Light::Spot(SpotLight {
                position,
                direction: world.transform_vector3(-Vec3::Z).normalize(),
                intensity,
                cos_inner: inner.cos(),
                cos_outer: outer.cos(),
            }))
        }
        // A zero scale leaves no direction: refused by Scene::add_light.
        Kind::Directional => Ok(Light::Directional(DirectionalLight::new(
            world.transform_vector3(-Vec3::Z),
            intensity,
        ))),
    }
}

/// Whether a primitive mode makes triangles (lists, strips, fans).
pub(super) fn is_triangles(mode: gltf::mesh::Mode) -> bool {
    use gltf::mesh::Mode;
    matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    )
}

/// Triangles of a primitive from its vertex indices, as glTF 2.0 §3.7.2.1
/// builds them: strips alternate their winding so every triangle faces the
/// same way, fans share the first vertex. Empty for points and lines.
fn triangle_list(mode: gltf::mesh::Mode, flat: &[u32]) -> Vec<[u32; 3]> {
    use gltf::mesh::Mode;
    let n = flat.len();
    match mode {
        Mode::Triangles => flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        Mode::TriangleStrip => (0..n.saturating_sub(2))
            .map(|i| {
                let odd = i % 2;
                [flat[i], flat[i + 1 + odd], flat[i + 2 - odd]]
            })
            .collect(),
        Mode::TriangleFan => (1..n.saturating_sub(1))
            .map(|i| [flat[i], flat[i + 1], flat[0]])
            .collect(),
        Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip => Vec::new(),
    }
}

/// A GLB file's layout, checked before the gltf crate reads it: the
/// header's declared length is the file's (the crate subtracts the header
/// size from it unchecked: a declared length under 12 overflowed, found by
/// the fuzzer; a shorter one hid trailing bytes), and the chunks tile the
/// rest: the JSON chunk first, at most one BIN chunk second. The spec lets
/// chunks of other types follow, for readers to skip; the gltf crate skips
/// them only after a BIN chunk, so one right after the JSON chunk is
/// refused here with a clear message rather than the crate's.
fn check_glb_header(bytes: &[u8]) -> std::result::Result<(), String> {
    const JSON: u32 = 0x4E4F_534A;
    const BIN: u32 = 0x004E_4942;
    if !bytes.starts_with(b"glTF") {
        return Ok(());
    }
    let field = |at: usize| {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let Some(length) = field(8) else {
        return Err("the GLB file is shorter than its 12-byte header".into());
    };
    if length as usize != bytes.len() {
        return Err(format!(
            "the GLB header declares {length} bytes; the file has {}",
            bytes.len()
        ));
    }
    let mut at = 12usize;
    let mut index = 0;
    while at < bytes.len() {
        let (Some(len), Some(kind)) = (field(at), field(at + 4)) else {
            return Err(format!("GLB chunk {index} has a truncated header"));
        };
        let end = (at + 8)
            .checked_add(len as usize)
            .filter(|&e| e <= bytes.len());
        let Some(end) = end else {
            return Err(format!(
                "GLB chunk {index} declares {len} bytes, past the end of the file"
            ));
        };
        let allowed = match kind {
            JSON => index == 0,
            BIN => index == 1,
            _ => index >= 2,
        };
        if !allowed {
            return Err(format!(
                "GLB chunk {index} has type {kind:#010x}: the JSON chunk must come first, \
                 at most one BIN chunk second, and other chunks (unsupported right after \
                 the JSON chunk) only after them"
            ));
        }
        at = end;
        index += 1;
    }
    if index == 0 {
        return Err("the GLB file has no JSON chunk".into());
    }
    Ok(())
}
