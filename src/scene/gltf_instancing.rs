//! `EXT_mesh_gpu_instancing`: a node whose mesh stands at many places, each
//! given by per-instance TRANSLATION (VEC3), ROTATION (VEC4, a unit
//! quaternion) and SCALE (VEC3) accessors of one count, any of them absent
//! (identity). Instance `i` is the node's world transform times
//! `T_i R_i S_i`; the node's light and camera are not instanced.
//!
//! The engine has no instancing of its own: each instance is a mesh of its
//! own, as a node shared by several parents is. The count is read from the
//! accessors before any vertex is, and counted in the graph's bound on the
//! triangles a scene expands to ([`super::gltf_graph`]). Attributes whose
//! names start with `_` (an application's own) are ignored.

use super::gltf_checks::label;
use super::gltf_quantized::read_f32_vectors;
use crate::error::{Error, Result};
use glam::{Mat4, Quat, Vec3};
use gltf::json::Root;
use serde_json::{Map, Value};

/// The extension's name.
pub(super) const EXT_MESH_GPU_INSTANCING: &str = "EXT_mesh_gpu_instancing";

/// The attributes the extension defines, with their component counts.
const ATTRIBUTES: [(&str, usize); 3] = [("TRANSLATION", 3), ("ROTATION", 4), ("SCALE", 3)];

/// The accessor of each attribute (`None`: absent), in [`ATTRIBUTES`]' order.
type Accessors = [Option<usize>; 3];

fn bad(node: &str, why: String) -> Error {
    Error::InvalidScene(format!("{node}: {EXT_MESH_GPU_INSTANCING}: {why}"))
}

/// The instance attributes of a node's extension object `ext`, checked
/// against the document's accessors (index, type and a common count);
/// returns them and the instance count.
fn attributes(root: &Root, node: &str, ext: &Value) -> Result<(Accessors, u64)> {
    let Some(attrs) = ext.get("attributes").and_then(Value::as_object) else {
        return Err(bad(node, "it has no `attributes` object".into()));
    };
    let mut accessors: Accessors = [None; 3];
    let mut count = None;
    for (name, value) in attrs {
        if name.starts_with('_') {
            continue;
        }
        let Some(slot) = ATTRIBUTES.iter().position(|(a, _)| a == name) else {
            return Err(bad(
                node,
                format!(
                    "attribute `{name}` is not supported (TRANSLATION, ROTATION, SCALE, or an \
                     application's own, named `_...`)"
                ),
            ));
        };
        let index = value
            .as_u64()
            .map(|i| i as usize)
            .filter(|&i| i < root.accessors.len())
            .ok_or_else(|| bad(node, format!("{name} names no accessor ({value})")))?;
        let n = root.accessors[index].count.0;
        if *count.get_or_insert(n) != n || n == 0 {
            return Err(bad(
                node,
                format!("its attributes must have one count of at least 1; {name} has {n}"),
            ));
        }
        accessors[slot] = Some(index);
    }
    let count =
        count.ok_or_else(|| bad(node, "it has no TRANSLATION, ROTATION or SCALE".into()))?;
    Ok((accessors, count))
}

/// The extension object of node `node`'s JSON extensions, if any.
fn extension(others: Option<&Map<String, Value>>) -> Option<&Value> {
    others?.get(EXT_MESH_GPU_INSTANCING)
}

/// How many instances of its mesh node `n` stands for: 1 without the
/// extension (or without a mesh, which the extension then leaves alone).
///
/// # Errors
/// [`Error::InvalidScene`] naming the node for a malformed extension.
pub(super) fn instance_count(root: &Root, n: usize) -> Result<u64> {
    let node = &root.nodes[n];
    let others = node.extensions.as_ref().map(|e| &e.others);
    match (extension(others), node.mesh) {
        (Some(ext), Some(_)) => {
            let name = label("node", n, node.name.as_deref());
            Ok(attributes(root, &name, ext)?.1)
        }
        _ => Ok(1),
    }
}

/// The transforms `T_i R_i S_i` of node `node`'s instances, in instance
/// order; `None` without the extension or without a mesh.
///
/// # Errors
/// [`Error::InvalidScene`] naming the node for a malformed extension, an
/// accessor of the wrong type or past its buffer, a component that is not
/// finite, or a rotation of length 0.
pub(super) fn transforms(
    node: &gltf::Node,
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
) -> Result<Option<Vec<Mat4>>> {
    let (Some(ext), Some(_)) = (extension(node.extensions()), node.mesh()) else {
        return Ok(None);
    };
    let name = label("node", node.index(), node.name());
    let (accessors, count) = attributes(doc.as_json(), &name, ext)?;
    let read = |slot: usize| -> Result<Option<Vec<[f32; 4]>>> {
        let Some(index) = accessors[slot] else {
            return Ok(None);
        };
        let accessor = doc
            .accessors()
            .nth(index)
            .ok_or_else(|| bad(&name, format!("no accessor {index}")))?;
        let values: Vec<[f32; 4]> = if ATTRIBUTES[slot].1 == 4 {
            read_f32_vectors::<4>(&accessor, buffers)?
        } else {
            read_f32_vectors::<3>(&accessor, buffers)?
                .into_iter()
                .map(|[x, y, z]| [x, y, z, 0.0])
                .collect()
        };
        if let Some(v) = values.iter().flatten().find(|v| !v.is_finite()) {
            return Err(bad(&name, format!("{} holds {v}", ATTRIBUTES[slot].0)));
        }
        Ok(Some(values))
    };
    let (t, r, s) = (read(0)?, read(1)?, read(2)?);
    let at = |v: &Option<Vec<[f32; 4]>>, i: usize| v.as_ref().map(|v| v[i]);
    (0..count as usize)
        .map(|i| {
            let translation = at(&t, i).map_or(Vec3::ZERO, |[x, y, z, _]| Vec3::new(x, y, z));
            let scale = at(&s, i).map_or(Vec3::ONE, |[x, y, z, _]| Vec3::new(x, y, z));
            let rotation = match at(&r, i) {
                None => Quat::IDENTITY,
                Some(q) => {
                    let q = Quat::from_array(q);
                    // Unit by the extension; a quantized one is a little off.
                    if q.length() < 1e-3 {
                        return Err(bad(&name, format!("instance {i} has the rotation {q}")));
                    }
                    q.normalize()
                }
            };
            Ok(Mat4::from_scale_rotation_translation(
                scale,
                rotation,
                translation,
            ))
        })
        .collect::<Result<Vec<_>>>()
        .map(Some)
}
