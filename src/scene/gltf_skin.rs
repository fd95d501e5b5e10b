//! A skinned glTF mesh in its rest pose: glTF 2.0 §3.7.3.3 places each
//! vertex by its joints, `sum_k w_k * world(joint_k) * inverseBind_k * v`,
//! and ignores the transform of the node the mesh hangs from. Animations
//! are not read, so the joints stand where the node hierarchy puts them.
//!
//! [`JointMatrices`] are built once per skinned node from the skin's
//! joints and `inverseBindMatrices` (identity when absent); [`Skinning`]
//! once per primitive from them, `JOINTS_0` and `WEIGHTS_0`, and it then
//! transforms the primitive's positions and normals like a node's matrix
//! does for an unskinned one.

use super::gltf_checks::label;
use super::gltf_quantized::read_f32_vectors;
use crate::error::{Error, Result};
use glam::{Mat3, Mat4, Vec3};
use gltf::accessor::DataType;
use gltf::mesh::Semantic;

/// A skin's `world(joint) * inverseBind`, one per joint, and its label
/// for messages.
pub(super) struct JointMatrices {
    name: String,
    matrices: Vec<Mat4>,
}

impl JointMatrices {
    /// Those of `skin`, whose nodes' world transforms are `worlds` (by
    /// node index; `None` for a node outside the scene).
    pub(super) fn of(
        skin: &gltf::Skin,
        buffers: &[Vec<u8>],
        worlds: &[Option<Mat4>],
    ) -> Result<Self> {
        let name = label("skin", skin.index(), skin.name());
        match joint_matrices(skin, buffers, worlds) {
            Ok(matrices) => Ok(JointMatrices { name, matrices }),
            Err(why) => Err(Error::InvalidScene(format!("{name}: {why}"))),
        }
    }
}

/// A primitive's joints and weights, and its skin's joint matrices: each
/// vertex's matrix is blended when asked for (stored, one 64-byte matrix a
/// vertex would be five times the positions' memory).
pub(super) struct Skinning<'a> {
    joint_matrices: &'a [Mat4],
    joints: Vec<[f32; 4]>,
    weights: Vec<[f32; 4]>,
}

impl<'a> Skinning<'a> {
    /// The rest pose of primitive `prim` of a mesh skinned by the skin of
    /// joint matrices `skin`; `Ok(None)` when the primitive has no
    /// `JOINTS_0`/`WEIGHTS_0`.
    pub(super) fn of(
        skin: &'a JointMatrices,
        prim: &gltf::Primitive,
        buffers: &[Vec<u8>],
    ) -> Result<Option<Self>> {
        let (Some(joints), Some(weights)) = (
            prim.get(&Semantic::Joints(0)),
            prim.get(&Semantic::Weights(0)),
        ) else {
            return Ok(None);
        };
        let bad = |why: String| Error::InvalidScene(format!("{}: {why}", skin.name));
        let joint_matrices = &skin.matrices[..];
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
            // glTF allows FLOAT alone here (the reader would dequantize others).
            if a.data_type() != DataType::F32 {
                return Err(format!(
                    "its inverseBindMatrices are {:?}, not FLOAT MAT4",
                    a.data_type()
                ));
            }
            if a.count() < count {
                return Err(format!(
                    "it has {count} joints but {} inverseBindMatrices",
                    a.count()
                ));
            }
            read_f32_vectors::<16>(&a, buffers)
                .map_err(|e| format!("its inverseBindMatrices: {e}"))?
                .iter()
                .map(Mat4::from_cols_array)
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
