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

/// A primitive's joints and weights, and its skin's joint matrices: each
/// vertex's matrix is blended when asked for (stored, one 64-byte matrix a
/// vertex would be five times the positions' memory).
pub(super) struct Skinning {
    joint_matrices: Vec<Mat4>,
    joints: Vec<[f32; 4]>,
    weights: Vec<[f32; 4]>,
}

impl Skinning {
    /// The rest pose of primitive `prim` of a mesh skinned by `skin`, whose
    /// nodes' world transforms are `worlds` (by node index; `None` for a
    /// node outside the scene); `Ok(None)` when the primitive has no
    /// `JOINTS_0`/`WEIGHTS_0`.
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
        for (v, (j, w)) in joints.iter().zip(&weights).enumerate() {
            let total: f32 = w.iter().sum();
            if !(total.is_finite() && total > 0.0 && w.iter().all(|&x| x >= 0.0)) {
                return Err(bad(format!(
                    "vertex {v} has the weights {w:?}: they must be finite, non-negative and not all 0"
                )));
            }
            // JOINTS_0 holds small unsigned integers, read exactly as floats.
            let unknown = j.iter().zip(w).find(|&(&joint, &weight)| {
                weight > 0.0
                    && !(joint >= 0.0
                        && joint.fract() == 0.0
                        && (joint as usize) < joint_matrices.len())
            });
            if let Some((joint, _)) = unknown {
                return Err(bad(format!(
                    "vertex {v} names joint {joint}, but the skin has {}",
                    joint_matrices.len()
                )));
            }
        }
        Ok(Some(Skinning {
            joint_matrices,
            joints,
            weights,
        }))
    }

    /// The vertex count the primitive's attributes must have.
    pub(super) fn len(&self) -> usize {
        self.joints.len()
    }

    /// Vertex `v`'s matrix: its joints' matrices by its weights, divided by
    /// their sum (meant to be 1; a rounded sum must not scale the vertex).
    fn matrix(&self, v: usize) -> Mat4 {
        let (j, w) = (self.joints[v], self.weights[v]);
        let total: f32 = w.iter().sum();
        j.iter()
            .zip(w)
            .filter(|&(_, weight)| weight > 0.0)
            .fold(Mat4::ZERO, |m, (&joint, weight)| {
                m + self.joint_matrices[joint as usize] * (weight / total)
            })
    }

    /// Position `p` of vertex `v`, posed.
    pub(super) fn point(&self, v: usize, p: Vec3) -> Vec3 {
        self.matrix(v).transform_point3(p)
    }

    /// Normal `n` of vertex `v`, posed (by the inverse transpose).
    pub(super) fn normal(&self, v: usize, n: Vec3) -> Vec3 {
        Mat3::from_mat4(self.matrix(v)).inverse().transpose() * n
    }

    /// Whether the pose mirrors the mesh (a negative determinant at its
    /// first vertex), which reverses its winding as a node's would.
    pub(super) fn mirrors(&self) -> bool {
        self.len() > 0 && Mat3::from_mat4(self.matrix(0)).determinant() < 0.0
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
