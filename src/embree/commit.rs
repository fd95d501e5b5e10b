//! Embree as the engine's [`RayCaster`], and [`Scene::commit`]: a scene and
//! its Embree geometry, owned together.

use super::{CommittedScene, Device, HitFilter};
use crate::error::{Error, Result};
use crate::raycast::{Hit, Ray, RayCaster};
use crate::scene::{PreparedScene, Scene};
use std::sync::Arc;

/// A scene prepared for tracing with Embree.
pub type EmbreeScene = PreparedScene<CommittedScene>;

impl RayCaster for CommittedScene {
    #[inline]
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        CommittedScene::intersect(self, ray)
    }

    #[inline]
    fn occluded(&self, ray: &Ray) -> bool {
        CommittedScene::occluded(self, ray)
    }

    fn intersect_batch(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        let n = rays.len().min(hits.len());
        CommittedScene::intersect_batch(self, &rays[..n], &mut hits[..n]);
    }

    fn occluded_batch(&self, rays: &[Ray], out: &mut [bool]) {
        let n = rays.len().min(out.len());
        CommittedScene::occluded_batch(self, &rays[..n], &mut out[..n]);
    }

    fn kernels(&self) -> Option<crate::isa::Kernels> {
        CommittedScene::kernels(self)
    }

    /// Holes are cut by the geometries' hit filters ([`Scene::embree_geometry`]).
    fn cuts_alpha_masks(&self) -> bool {
        true
    }

    /// One Embree geometry per mesh, in order, each with its mesh's material.
    fn check_scene(&self, scene: &Scene) -> Result<()> {
        if self.geometry_count() != scene.meshes.len() {
            return Err(Error::InvalidScene(format!(
                "the Embree scene has {} geometries but the scene has {} meshes: \
                 it was built from another scene",
                self.geometry_count(),
                scene.meshes.len()
            )));
        }
        for (g, mesh) in scene.meshes.iter().enumerate() {
            let m = self.material(g as u32);
            if m != Some(mesh.material as u32) || mesh.material >= scene.materials.len() {
                return Err(Error::InvalidScene(format!(
                    "mesh {g} has material {} but its Embree geometry has {m:?} \
                     (of {} materials): it was built from another scene",
                    mesh.material,
                    scene.materials.len()
                )));
            }
        }
        // Geometries with holes were added with a filter, the others without.
        let holed = (0..scene.meshes.len())
            .filter(|&m| scene.mesh_has_holes(m))
            .count();
        if holed != self.filtered_count() {
            return Err(Error::InvalidScene(format!(
                "the scene has {holed} meshes with alpha-mask holes but the Embree scene has \
                 {} filtered geometries: it was built from another scene",
                self.filtered_count()
            )));
        }
        Ok(())
    }
}

#[cfg_attr(docsrs, doc(cfg(feature = "embree")))]
impl Scene {
    /// Hands the geometry to Embree and keeps the scene with it: the result
    /// is `'static`, `Send + Sync`, and what a [`crate::engine::Tracer`]
    /// traces. A hit's `material` is the mesh's material index and its
    /// `geom_id` the mesh index. A mesh whose alpha mask cuts holes gets a
    /// hit filter ([`Scene::cutout`], [`super::HitFilter`]): every ray
    /// passes through its holes.
    ///
    /// # Errors
    /// [`Error::Embree`] when Embree rejects the geometry; what
    /// [`PreparedScene::new`] refuses (no light, no triangle).
    pub fn commit(self, device: &Device) -> Result<EmbreeScene> {
        let rt = self.embree_geometry(device)?;
        PreparedScene::new(self, rt)
    }

    /// The Embree half only, for sharing one geometry among scenes that
    /// differ in their lights' profiles (wrap it in an `Arc` and pass it to
    /// [`PreparedScene::new`], which checks it against each scene).
    ///
    /// # Errors
    /// [`Error::Embree`] when Embree rejects the geometry.
    pub fn embree_geometry(&self, device: &Device) -> Result<CommittedScene> {
        let mut builder = device.scene_builder()?;
        for (i, m) in self.meshes.iter().enumerate() {
            let material = m.material as u32;
            match self.cutout(i) {
                // Only meshes whose mask cuts holes pay for a filter.
                Some(cutout) => {
                    let filter: HitFilter = Arc::new(move |prim, u, v| !cutout.is_hole(prim, u, v));
                    builder.add_triangles_with_filter(&m.positions, &m.indices, material, filter)?
                }
                None => builder.add_triangles(&m.positions, &m.indices, material)?,
            };
        }
        builder.commit()
    }
}
