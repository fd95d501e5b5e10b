//! A skinned glTF mesh in its rest pose: glTF 2.0 §3.7.3.3 places each
//! vertex by its joints, `sum_k w_k * world(joint_k) * inverseBind_k * v`,
//! and ignores the transform of the node the mesh hangs from. Animations
//! are not read, so the joints stand where the node hierarchy puts them.
//!
//! [`Skinning`] is built once per primitive from `JOINTS_0`, `WEIGHTS_0`
//! and the skin's `inverseBindMatrices` (identity when absent), and then
//! transforms the primitive's positions and normals like a node's matrix
//! does for an unskinned one.

use super::gltf_checks::label;
use super::gltf_quantized::read_f32_vectors;
use crate::error::{Error, Result};
use glam::{Mat3, Mat4, Vec3, Vec4};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Semantic;

/// One matrix per vertex, blended from its joints' matrices.
pub(super) struct Skinning {
    matrices: Vec<Mat4>,
}

impl Skinning {
    /// The rest-pose matrices of primitive `prim` of a mesh skinned by
    /// `skin`, whose nodes' world transforms are `worlds` (by node index;
    /// `None` for a node outside the scene); `Ok(None)` when the primitive
    /// has no `JOINTS_0`/`WEIGHTS_0`.
    pub(super) fn of(
        skin: &gltf::Skin,
        prim: &gltf::Primitive,
        buffers: &[Vec<u8>],
        worlds: &[Option<Mat4>],
    ) -> Result<Option<Self>> {
        let (Some(joints), Some(weights)) = (
            prim.get(&Semantic::Joints(0)),
            prim.get(&Semantic::Weights(0)),
        ) else {
            return Ok(None);
        };
        let name = label("skin", skin.index(), skin.name());
        let bad = |why: String| Error::InvalidScene(format!("{name}: {why}"));
        let joint_matrices = joint_matrices(skin, buffers, worlds).map_err(bad)?;
        let joints = read_f32_vectors::<4>(&joints, buffers)?;
        let weights = read_f32_vectors::<4>(&weights, buffers)?;
        if joints.len() != weights.len() {
            return Err(bad(format!(
                "JOINTS_0 has {} elements and WEIGHTS_0 {}",
                joints.len(),
                weights.len()
            )));
        }
        let mut matrices = Vec::with_capacity(joints.len());
        for (v, (j, w)) in joints.iter().zip(&weights).enumerate() {
            let total: f32 = w.iter().sum();
            if !(total.is_finite() && total > 0.0 && w.iter().all(|&x| x >= 0.0)) {
                return Err(bad(format!(
                    "vertex {v} has the weights {w:?}: they must be finite, non-negative and not all 0"
                )));
            }
            let mut m = Mat4::ZERO;
            for (&joint, &weight) in j.iter().zip(w) {
                if weight == 0.0 {
                    continue;
                }
                // JOINTS_0 holds small unsigned integers (read exactly as floats).
                let matrix = joint_matrices.get(joint as usize).ok_or_else(|| {
                    bad(format!(
                        "vertex {v} names joint {joint}, but the skin has {}",
                        joint_matrices.len()
                    ))
                })?;
                // Weights are meant to sum to 1; dividing keeps a rounded
                // sum from scaling the vertex.
                m += *matrix * (weight / total);
            }
            matrices.push(m);
        }
        Ok(Some(Skinning { matrices }))
    }

    /// The vertex count the primitive's attributes must have.
    pub(super) fn len(&self) -> usize {
        self.matrices.len()
    }

    /// Position `p` of vertex `v`, posed.
    pub(super) fn point(&self, v: usize, p: Vec3) -> Vec3 {
        self.matrices[v].transform_point3(p)
    }

    /// Normal `n` of vertex `v`, posed (by the inverse transpose).
    pub(super) fn normal(&self, v: usize, n: Vec3) -> Vec3 {
        Mat3::from_mat4(self.matrices[v]).inverse().transpose() * n
    }

    /// Whether the pose mirrors the mesh (a negative determinant at its
    /// first vertex), which reverses its winding as a node's would.
    pub(super) fn mirrors(&self) -> bool {
        self.matrices
            .first()
            .is_some_and(|m| Mat3::from_mat4(*m).determinant() < 0.0)
    }
}

/// `world(joint) * inverseBind` for every joint of `skin`.
fn joint_matrices(
    skin: &gltf::Skin,
    buffers: &[Vec<u8>],
    worlds: &[Option<Mat4>],
) -> std::result::Result<Vec<Mat4>, String> {
    let count = skin.joints().len();
    let inverse_binds = match skin.inverse_bind_matrices() {
        None => vec![Mat4::IDENTITY; count],
        Some(a) => {
            if a.data_type() != DataType::F32 || a.dimensions() != Dimensions::Mat4 {
                return Err(format!(
                    "its inverseBindMatrices are {:?} {:?}, not FLOAT MAT4",
                    a.data_type(),
                    a.dimensions()
                ));
            }
            if a.count() < count {
                return Err(format!(
                    "it has {count} joints but {} inverseBindMatrices",
                    a.count()
                ));
            }
            let columns = read_columns(&a, buffers)?;
            columns
                .chunks_exact(4)
                .map(|c| Mat4::from_cols(c[0], c[1], c[2], c[3]))
                .collect()
        }
    };
    skin.joints()
        .zip(inverse_binds)
        .map(|(joint, inverse_bind)| {
            let world = worlds
                .get(joint.index())
                .copied()
                .flatten()
                .ok_or_else(|| format!("its joint node {} is not in the scene", joint.index()))?;
            let m = world * inverse_bind;
            if m.is_finite() {
                Ok(m)
            } else {
                Err(format!(
                    "joint node {}'s matrix is not finite",
                    joint.index()
                ))
            }
        })
        .collect()
}

/// A FLOAT MAT4 accessor's elements as columns, four per matrix; its byte
/// range is checked by the loader before any accessor is read.
fn read_columns(a: &gltf::Accessor, buffers: &[Vec<u8>]) -> std::result::Result<Vec<Vec4>, String> {
    let view = a
        .view()
        .ok_or("its inverseBindMatrices have no bufferView")?;
    let data = buffers
        .get(view.buffer().index())
        .ok_or("its inverseBindMatrices' buffer is missing")?;
    let stride = view.stride().unwrap_or(64);
    let base = view.offset() + a.offset();
    let mut out = Vec::with_capacity(a.count() * 4);
    for i in 0..a.count() {
        let start = base + i * stride;
        let bytes = data
            .get(start..start + 64)
            .filter(|_| start + 64 <= view.offset() + view.length())
            .ok_or("its inverseBindMatrices lie past their bufferView")?;
        let f: Vec<f32> = bytes
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        for c in f.chunks_exact(4) {
            out.push(Vec4::new(c[0], c[1], c[2], c[3]));
        }
    }
    Ok(out)
}
