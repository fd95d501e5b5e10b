//! A scene together with the ray caster built from it: what a
//! [`crate::engine::Tracer`] traces. Owning both halves means a tracer can
//! never be handed one scene's materials and another scene's geometry, and
//! the pair is `'static`: cheap to put in an `Arc`, store and share.
//!
//! With Embree, [`Scene::commit`] makes one (see `src/embree/commit.rs`); with
//! a caster of your own, [`PreparedScene::new`].

use super::Scene;
use crate::error::Result;
use crate::raycast::RayCaster;

/// A [`Scene`] and its ray caster `C`, checked against each other once.
#[derive(Debug)]
pub struct PreparedScene<C> {
    scene: Scene,
    caster: C,
}

impl<C: RayCaster> PreparedScene<C> {
    /// Puts a scene and a caster built from it together. This is where a
    /// scene is checked ([`Scene::validate`]) for tracing and rendering: a
    /// prepared scene cannot change, so the tracer and the renderer trust it.
    ///
    /// # Errors
    /// What [`Scene::validate`] reports (no light, no triangle, lights too
    /// bright together), and what [`RayCaster::check_scene`] reports (with
    /// Embree: a geometry or material count that does not match the scene's
    /// meshes, or a mesh with holes whose geometry has no hit filter); a
    /// scene with alpha-mask holes for a caster that does not cut them
    /// ([`RayCaster::cuts_alpha_masks`]).
    pub fn new(scene: Scene, caster: C) -> Result<Self> {
        scene.validate()?;
        caster.check_scene(&scene)?;
        if !caster.cuts_alpha_masks() {
            if let Some(mesh) = (0..scene.meshes.len()).find(|&m| scene.mesh_has_holes(m)) {
                let m = &scene.meshes[mesh];
                return Err(crate::Error::InvalidScene(format!(
                    "mesh `{}` has material `{}` with an alpha mask that cuts holes \
                     (alphaMode MASK), but the ray caster does not cut them \
                     (RayCaster::cuts_alpha_masks): its cut-outs would be traced as walls",
                    m.name, scene.materials[m.material].name
                )));
            }
        }
        Ok(PreparedScene { scene, caster })
    }
}

impl<C> PreparedScene<C> {
    /// The scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The ray caster.
    pub fn caster(&self) -> &C {
        &self.caster
    }
}
