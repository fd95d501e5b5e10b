//! Validation of a glTF document before anything trusts it.
//!
//! The gltf crate's accessors (`Node::mesh`, `Camera::projection`,
//! `Light::kind`, the accessor readers, ...) index and `unwrap` without
//! checking; a hostile file makes them panic, loop or allocate without bound.
//! `check_document` runs on the parsed JSON before any of them is called and
//! checks every reference, enum and number the loader uses; `gltf_data`
//! then checks every byte range against the loaded buffers, and
//! `gltf_graph` the node graph. Each problem is one
//! [`Error::InvalidScene`] naming the node, mesh, accessor, camera or light.
//!

use crate::error::{Error, Result};
use gltf::json::accessor::{ComponentType, Type};
use gltf::json::validation::Checked;
use gltf::json::{self, Root};

/// Node instances a scene may expand to (nodes reached through every path).
pub const MAX_NODE_INSTANCES: u64 = 1 << 20;
/// Triangles a scene may expand to once every mesh instance is placed
/// (about 48 bytes each while loading: 16 M triangles stay under 1 GB).
pub const MAX_INSTANCED_TRIANGLES: u64 = 1 << 24;
/// Elements of an accessor that no buffer bytes back (a sparse accessor
/// without a `bufferView` starts as `count` zeros).
pub const MAX_UNBACKED_ELEMENTS: u64 = 1 << 22;

fn bad(msg: String) -> Error {
    Error::InvalidScene(msg)
}

/// `kind i (`name`)`, the way every message names an object.
pub(super) fn label(kind: &str, i: usize, name: Option<&str>) -> String {
    match name {
        Some(n) => format!("{kind} {i} (`{n}`)"),
        None => format!("{kind} {i}"),
    }
}

fn index_ok<T>(what: &str, idx: json::Index<T>, len: usize) -> Result<usize> {
    let i = idx.value();
    if i < len {
        Ok(i)
    } else {
        Err(bad(format!(
            "{what} refers to index {i}, but there are only {len}"
        )))
    }
}

/// Bytes of one component.
pub(super) fn component_size(c: ComponentType) -> u64 {
    match c {
        ComponentType::I8 | ComponentType::U8 => 1,
        ComponentType::I16 | ComponentType::U16 => 2,
        ComponentType::U32 | ComponentType::F32 => 4,
    }
}

/// Components of one element.
pub(super) fn multiplicity(t: Type) -> u64 {
    match t {
        Type::Scalar => 1,
        Type::Vec2 => 2,
        Type::Vec3 => 3,
        Type::Vec4 | Type::Mat2 => 4,
        Type::Mat3 => 9,
        Type::Mat4 => 16,
    }
}

/// The extensions a file may require: those the loader reads, and
/// `KHR_texture_basisu`, whose textures (with no PNG, JPEG or WebP image)
/// load with their factors alone and a warning.
const SUPPORTED_REQUIRED: [&str; 15] = [
    "KHR_lights_punctual",
    super::gltf_meshopt::EXT_MESHOPT_COMPRESSION,
    super::gltf_meshopt::KHR_MESHOPT_COMPRESSION,
    super::gltf_instancing::EXT_MESH_GPU_INSTANCING,
    super::gltf_quantized::KHR_MESH_QUANTIZATION,
    "KHR_materials_clearcoat",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_sheen",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_texture_transform",
    "KHR_texture_basisu",
    "EXT_texture_webp",
];

/// The extensions of `extensionsUsed` that the loader neither reads nor
/// names elsewhere (a material's unread extension is named with its
/// material): what they add to the file is ignored, which the loader says.
pub(super) fn unread_extensions(root: &Root) -> impl Iterator<Item = &str> {
    root.extensions_used
        .iter()
        .map(String::as_str)
        .filter(|e| !SUPPORTED_REQUIRED.contains(e) && !e.starts_with("KHR_materials_"))
}

/// Checks the document's structure; no buffer data is needed.
pub(super) fn check_document(root: &Root) -> Result<()> {
    // glTF 2.0: a loader must refuse a file that requires an extension it
    // does not support (a Draco-compressed mesh read as plain data would be
    // wrong geometry, silently).
    if let Some(ext) = root
        .extensions_required
        .iter()
        .find(|e| !SUPPORTED_REQUIRED.contains(&e.as_str()))
    {
        return Err(bad(format!(
            "the file requires the extension `{ext}`, which is not supported (supported: {})",
            SUPPORTED_REQUIRED.join(", ")
        )));
    }
    for (i, a) in root.accessors.iter().enumerate() {
        let name = label("accessor", i, a.name.as_deref());
        if !matches!(a.component_type, Checked::Valid(_)) || !matches!(a.type_, Checked::Valid(_)) {
            return Err(bad(format!("{name} has an unknown componentType or type")));
        }
        if let Some(v) = a.buffer_view {
            index_ok(&name, v, root.buffer_views.len())?;
        } else if a.count.0 > MAX_UNBACKED_ELEMENTS {
            return Err(bad(format!(
                "{name} has count {} without a bufferView (at most {MAX_UNBACKED_ELEMENTS})",
                a.count.0
            )));
        }
        if let Some(s) = &a.sparse {
            index_ok(
                &format!("{name} sparse indices"),
                s.indices.buffer_view,
                root.buffer_views.len(),
            )?;
            index_ok(
                &format!("{name} sparse values"),
                s.values.buffer_view,
                root.buffer_views.len(),
            )?;
            if !matches!(s.indices.component_type, Checked::Valid(_)) {
                return Err(bad(format!("{name} has sparse indices of an unknown type")));
            }
            if s.count.0 == 0 || s.count.0 > a.count.0 {
                return Err(bad(format!(
                    "{name} has a sparse count {} outside 1..={}",
                    s.count.0, a.count.0
                )));
            }
        }
    }
    for (i, v) in root.buffer_views.iter().enumerate() {
        let name = label("bufferView", i, v.name.as_deref());
        index_ok(&name, v.buffer, root.buffers.len())?;
        if let Some(s) = v.byte_stride {
            if !(4..=252).contains(&s.0) || s.0 % 4 != 0 {
                return Err(bad(format!(
                    "{name} has byteStride {}, not a multiple of 4 in 4..=252",
                    s.0
                )));
            }
        }
    }
    for (i, m) in root.meshes.iter().enumerate() {
        check_mesh(root, i, m)?;
    }
    for (i, c) in root.cameras.iter().enumerate() {
        check_camera(i, c)?;
    }
    let lights = root
        .extensions
        .as_ref()
        .and_then(|e| e.khr_lights_punctual.as_ref())
        .map_or(&[][..], |l| &l.lights[..]);
    for (i, l) in lights.iter().enumerate() {
        check_light(i, l)?;
    }
    for (i, n) in root.nodes.iter().enumerate() {
        check_node(root, i, n, lights.len())?;
    }
    // The gltf crate unwraps a skin's indices when asked for its parts.
    for (i, skin) in root.skins.iter().enumerate() {
        let name = label("skin", i, skin.name.as_deref());
        for &j in &skin.joints {
            index_ok(&format!("{name} joint"), j, root.nodes.len())?;
        }
        if let Some(s) = skin.skeleton {
            index_ok(&format!("{name} skeleton"), s, root.nodes.len())?;
        }
        if let Some(a) = skin.inverse_bind_matrices {
            index_ok(
                &format!("{name} inverseBindMatrices"),
                a,
                root.accessors.len(),
            )?;
        }
    }
    if let Some(s) = root.scene {
        index_ok("the default scene", s, root.scenes.len())?;
    }
    for (i, s) in root.scenes.iter().enumerate() {
        for &n in &s.nodes {
            index_ok(&label("scene", i, s.name.as_deref()), n, root.nodes.len())?;
        }
    }
    super::gltf_textures::check_json(root)
}

fn check_mesh(root: &Root, i: usize, m: &json::Mesh) -> Result<()> {
    let name = label("mesh", i, m.name.as_deref());
    for (pi, p) in m.primitives.iter().enumerate() {
        let here = format!("{name} primitive {pi}");
        if !matches!(p.mode, Checked::Valid(_)) {
            return Err(bad(format!("{here} has an unknown mode")));
        }
        if let Some(mat) = p.material {
            index_ok(&here, mat, root.materials.len())?;
        }
        for (sem, &a) in &p.attributes {
            let Checked::Valid(sem) = sem else {
                return Err(bad(format!("{here} has an attribute of unknown semantic")));
            };
            let ai = index_ok(
                &format!("{here} attribute {sem:?}"),
                a,
                root.accessors.len(),
            )?;
            super::gltf_quantized::check_attribute(root, sem, ai)
                .map_err(|why| bad(format!("{here}: {why}")))?;
            if *sem == json::mesh::Semantic::Positions {
                let acc = &root.accessors[ai];
                if acc.min.is_none() || acc.max.is_none() {
                    return Err(bad(format!(
                        "{here}: its POSITION {} has no min and max (glTF 2.0 requires both)",
                        label("accessor", ai, acc.name.as_deref())
                    )));
                }
                if acc.buffer_view.is_none() && acc.sparse.is_none() {
                    return Err(bad(format!(
                        "{here}: its POSITION {} has neither a bufferView nor sparse data",
                        label("accessor", ai, acc.name.as_deref())
                    )));
                }
            }
        }
        if let Some(ix) = p.indices {
            let ai = index_ok(&format!("{here} indices"), ix, root.accessors.len())?;
            let acc = &root.accessors[ai];
            let int = matches!(
                acc.component_type,
                Checked::Valid(json::accessor::GenericComponentType(
                    ComponentType::U8 | ComponentType::U16 | ComponentType::U32
                ))
            );
            if !int || acc.type_ != Checked::Valid(Type::Scalar) {
                return Err(bad(format!(
                    "{here}: its index {} is not an unsigned integer SCALAR",
                    label("accessor", ai, acc.name.as_deref())
                )));
            }
        }
        // A triangle list has three vertices a triangle: a remainder was
        // dropped in silence before.
        let count = match p.indices {
            Some(ix) => root
                .accessors
                .get(ix.value())
                .map(|a| (a.count.0, "indices")),
            None => p
                .attributes
                .get(&Checked::Valid(json::mesh::Semantic::Positions))
                .and_then(|a| root.accessors.get(a.value()))
                .map(|a| (a.count.0, "positions")),
        };
        let triangles = matches!(p.mode, Checked::Valid(json::mesh::Mode::Triangles));
        if let Some((n, what)) = count.filter(|&(n, _)| triangles && n % 3 != 0) {
            return Err(bad(format!(
                "{here} is a triangle list of {n} {what}, not a multiple of 3"
            )));
        }
    }
    Ok(())
}

fn check_camera(i: usize, c: &json::Camera) -> Result<()> {
    use json::camera::Type as T;
    let name = label("camera", i, c.name.as_deref());
    match c.type_ {
        Checked::Valid(T::Perspective) => {
            let Some(p) = &c.perspective else {
                return Err(bad(format!(
                    "{name} is perspective but has no `perspective` object"
                )));
            };
            if !(p.yfov.is_finite() && p.yfov > 0.0 && p.yfov < std::f32::consts::PI) {
                return Err(bad(format!("{name} has yfov {}, outside (0, pi)", p.yfov)));
            }
            if let Some(a) = p.aspect_ratio.filter(|a| !(a.is_finite() && *a > 0.0)) {
                return Err(bad(format!("{name} has aspectRatio {a}; it must be > 0")));
            }
            Ok(())
        }
        Checked::Valid(T::Orthographic) if c.orthographic.is_none() => Err(bad(format!(
            "{name} is orthographic but has no `orthographic` object"
        ))),
        Checked::Valid(T::Orthographic) => Ok(()),
        Checked::Invalid => Err(bad(format!("{name} has an unknown type"))),
    }
}

fn check_light(i: usize, l: &json::extensions::scene::khr_lights_punctual::Light) -> Result<()> {
    use json::extensions::scene::khr_lights_punctual::Type as T;
    let name = label("light", i, l.name.as_deref());
    if !l.intensity.is_finite() || l.color.iter().any(|c| !c.is_finite()) {
        return Err(bad(format!("{name} has a non-finite color or intensity")));
    }
    if let Some(r) = l.range.filter(|r| !(r.is_finite() && *r > 0.0)) {
        return Err(bad(format!("{name} has range {r}; it must be > 0")));
    }
    match l.type_ {
        Checked::Invalid => Err(bad(format!("{name} has an unknown type"))),
        Checked::Valid(T::Spot) => {
            let Some(s) = &l.spot else {
                return Err(bad(format!(
                    "{name} is a spot light without a `spot` object"
                )));
            };
            let (inner, outer) = (s.inner_cone_angle, s.outer_cone_angle);
            let half = std::f32::consts::FRAC_PI_2;
            if !(outer.is_finite() && outer > 0.0 && outer <= half) {
                return Err(bad(format!(
                    "{name} has outerConeAngle {outer}, outside (0, pi/2]"
                )));
            }
            if !(inner.is_finite() && (0.0..outer).contains(&inner)) {
                return Err(bad(format!(
                    "{name} has innerConeAngle {inner}, outside [0, {outer})"
                )));
            }
            Ok(())
        }
        Checked::Valid(_) => Ok(()),
    }
}

fn check_node(root: &Root, i: usize, n: &json::Node, lights: usize) -> Result<()> {
    let name = label("node", i, n.name.as_deref());
    if let Some(m) = n.mesh {
        index_ok(&name, m, root.meshes.len())?;
    }
    if let Some(c) = n.camera {
        index_ok(&name, c, root.cameras.len())?;
    }
    if let Some(s) = n.skin {
        index_ok(&format!("{name} skin"), s, root.skins.len())?;
    }
    for &c in n.children.iter().flatten() {
        index_ok(&format!("{name} child"), c, root.nodes.len())?;
    }
    if let Some(l) = n
        .extensions
        .as_ref()
        .and_then(|e| e.khr_lights_punctual.as_ref())
    {
        index_ok(&format!("{name} light"), l.light, lights)?;
    }
    let finite = n.matrix.iter().flatten().all(|x| x.is_finite())
        && n.translation.iter().flatten().all(|x| x.is_finite())
        && n.scale.iter().flatten().all(|x| x.is_finite())
        && n.rotation.iter().flat_map(|q| q.0).all(|x| x.is_finite());
    if !finite {
        return Err(bad(format!("{name} has a non-finite transform")));
    }
    if let Some(m) = n.matrix {
        if n.translation.is_some() || n.rotation.is_some() || n.scale.is_some() {
            return Err(bad(format!(
                "{name} has both a matrix and translation, rotation or scale"
            )));
        }
        check_trs_matrix(&name, &m)?;
    }
    // glTF rotations are unit quaternions; the matrix the gltf crate makes
    // of another is no rotation (it distorted the mesh, silently).
    if let Some(q) = n.rotation.map(|q| q.0) {
        let len = q.iter().map(|&x| f64::from(x).powi(2)).sum::<f64>().sqrt();
        if (len - 1.0).abs() > 1e-3 {
            return Err(bad(format!(
                "{name} has a rotation {q:?} of length {len}, not a unit quaternion"
            )));
        }
    }
    Ok(())
}

/// glTF 2.0 §3.5.3: a node's matrix must decompose into translation,
/// rotation and scale: its bottom row is (0, 0, 0, 1) (no projection) and
/// its three axes are orthogonal (no shear). Column-major, as in the file.
fn check_trs_matrix(name: &str, m: &[f32; 16]) -> Result<()> {
    let bottom = [m[3], m[7], m[11], m[15]];
    let off = bottom
        .iter()
        .zip([0.0, 0.0, 0.0, 1.0])
        .any(|(x, want)| (x - want).abs() > 1e-6);
    if off {
        return Err(bad(format!(
            "{name} has a matrix whose bottom row is {bottom:?}, not [0, 0, 0, 1]: \
             it is not a translation, rotation and scale"
        )));
    }
    let axis =
        |c: usize| glam::DVec3::new(m[4 * c].into(), m[4 * c + 1].into(), m[4 * c + 2].into());
    for (a, b) in [(0, 1), (1, 2), (0, 2)] {
        let (u, v) = (axis(a), axis(b));
        let scale = u.length() * v.length();
        if scale > 0.0 && u.dot(v).abs() > 1e-4 * scale {
            return Err(bad(format!(
                "{name} has a sheared matrix (its axes {a} and {b} are not orthogonal): \
                 it is not a translation, rotation and scale"
            )));
        }
    }
    Ok(())
}
