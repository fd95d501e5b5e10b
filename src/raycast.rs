//! Ray casting as the photon engine sees it: a [`Ray`], the [`Hit`] it
//! returns, and the [`RayCaster`] trait the tracer is generic over.
//!
//! Embree's scene (`embree::CommittedScene`, feature `embree`) implements the trait;
//! a renderer with its own BVH implements it too and drives the same engine
//! (see `examples/downstream`). Nothing here depends on Embree, so this
//! module, the scene model and the engine's shading build without it.
//!
//! Contract of an implementation:
//! - `Hit::material` indexes the [`Scene`]'s materials;
//! - `Hit::geom_id` is the index of the hit mesh in the scene and
//!   `Hit::prim_id` the triangle's index in it (the renderer interpolates
//!   that triangle's vertex normals);
//! - `Hit::ng` is the unit geometric normal, on either side (surfaces are
//!   two-sided: the engine flips it towards the incoming photon);
//! - `Hit::t` is in units of `Ray::dir`, within `[tnear, tfar]`;
//! - a ray that is not finite misses (and is not occluded);
//! - with [`RayCaster::cuts_alpha_masks`], a point of an alpha mask's hole
//!   ([`Scene::is_hole`]) is never hit nor occludes: rays pass through it.
//!
//! A hit that breaks the contract (an index the scene does not have, a `t`
//! that is NaN or outside the segment, a normal that is not finite and
//! non-zero: [`BadHit`]) makes the trace and the render fail with
//! [`crate::Error::InvalidScene`] naming it, never a panic or a silently
//! wrong map.

use crate::error::Result;
use crate::scene::Scene;
use glam::Vec3;
use std::sync::Arc;

/// Embree's `FLT_LARGE` (`common/math/constants.h`): `RayK::valid()`
/// asserts that every origin and direction coordinate is at most this in
/// magnitude. A ray beyond it aborts the process, so it never reaches Embree.
pub const EMBREE_LARGE: f32 = 1.844e18;

/// A ray segment `origin + t * dir`, `t` in `[tnear, tfar]`. `dir` need not
/// be unit length; `t` is measured in units of `dir`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Start point.
    pub origin: Vec3,
    /// Direction (non-zero, not necessarily normalised).
    pub dir: Vec3,
    /// Start of the segment (>= 0).
    pub tnear: f32,
    /// End of the segment (>= `tnear`, may be infinite).
    pub tfar: f32,
}

impl Ray {
    /// An unbounded ray: `tnear = 0`, `tfar = +inf`.
    #[inline]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Ray {
            origin,
            dir,
            tnear: 0.0,
            tfar: f32::INFINITY,
        }
    }

    /// The segment from `origin` towards `target`, stopping `eps` (a fraction
    /// of the distance) short of either end: for shadow and visibility tests.
    #[inline]
    pub fn segment(origin: Vec3, target: Vec3, eps: f32) -> Self {
        Ray {
            origin,
            dir: target - origin,
            tnear: eps,
            tfar: 1.0 - eps,
        }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.dir
    }
}

/// The closest intersection of a ray with the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit (distance when `dir` is unit length).
    pub t: f32,
    /// Unit geometric normal (not flipped toward the ray).
    pub ng: Vec3,
    /// Geometry ID (with Embree: the mesh index of the scene).
    pub geom_id: u32,
    /// Triangle index within that geometry.
    pub prim_id: u32,
    /// Barycentric coordinate of vertex 1 (`p = (1-u-v) p0 + u p1 + v p2`).
    pub u: f32,
    /// Barycentric coordinate of vertex 2.
    pub v: f32,
    /// Index of the hit surface's material in the scene.
    pub material: u32,
}

/// How a caster's hit broke the contract of [`RayCaster`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BadHit {
    /// A material index the scene does not have.
    Material(u32),
    /// A `geom_id` / `prim_id` pair the scene does not have.
    Primitive(u32, u32),
    /// A `t` that is NaN or outside `[tnear, tfar]`.
    Distance(f32),
    /// A normal that is not finite, or zero.
    Normal(Vec3),
}

impl std::fmt::Display for BadHit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BadHit::Material(m) => {
                write!(f, "a hit on material {m}, which the scene does not have")
            }
            BadHit::Primitive(g, p) => {
                write!(
                    f,
                    "a hit on triangle {p} of mesh {g}, which the scene does not have"
                )
            }
            BadHit::Distance(t) => write!(f, "a hit at t = {t}, outside the ray's segment"),
            BadHit::Normal(n) => {
                write!(f, "a hit with the normal {n}, not a finite non-zero vector")
            }
        }
    }
}

impl BadHit {
    /// The error a trace or render ends with.
    pub fn into_error(self, scene: &Scene) -> crate::Error {
        crate::Error::InvalidScene(format!(
            "the ray caster reported {self} ({} meshes, {} materials): it breaks the \
             RayCaster contract or was built from another scene",
            scene.meshes.len(),
            scene.materials.len()
        ))
    }
}

impl Hit {
    /// Checks this hit of `ray` against the caster contract and `scene`.
    ///
    /// # Errors
    /// The first [`BadHit`] found.
    #[inline]
    pub fn check(&self, ray: &Ray, scene: &Scene) -> std::result::Result<(), BadHit> {
        if !(self.t >= ray.tnear && self.t <= ray.tfar) {
            return Err(BadHit::Distance(self.t));
        }
        if !self.ng.is_finite() || self.ng == Vec3::ZERO {
            return Err(BadHit::Normal(self.ng));
        }
        let mesh = scene.meshes.get(self.geom_id as usize);
        if mesh.is_none_or(|m| self.prim_id as usize >= m.indices.len()) {
            return Err(BadHit::Primitive(self.geom_id, self.prim_id));
        }
        if self.material as usize >= scene.materials.len() {
            return Err(BadHit::Material(self.material));
        }
        Ok(())
    }

    /// The geometric normal on the side that a ray travelling along `dir`
    /// comes from: `-ng` when `dir` runs along `ng` (the ray arrives from
    /// behind), else `ng`. `facing(-out)` is the side a ray leaving along
    /// `out` starts on.
    #[inline]
    pub fn facing(&self, dir: Vec3) -> Vec3 {
        if self.ng.dot(dir) > 0.0 {
            -self.ng
        } else {
            self.ng
        }
    }
}

/// Something that finds where rays hit a scene: closest hits and occlusion,
/// one ray at a time or in batches. Shared by every tracing thread.
///
/// The batch methods are what the photon engine calls (a batch of up to
/// `TraceConfig::batch` rays at a time); their default loops over the single
/// queries, and an implementation with packet kernels overrides them.
pub trait RayCaster: Send + Sync {
    /// The closest hit along `ray` in `[tnear, tfar]`, if any.
    fn intersect(&self, ray: &Ray) -> Option<Hit>;

    /// Whether anything lies along `ray` in `[tnear, tfar]`.
    fn occluded(&self, ray: &Ray) -> bool;

    /// [`intersect`](Self::intersect) for every ray; `hits` has one slot per ray
    /// (extra slots on either side are left alone).
    fn intersect_batch(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        for (ray, hit) in rays.iter().zip(hits.iter_mut()) {
            *hit = self.intersect(ray);
        }
    }

    /// [`occluded`](Self::occluded) for every ray.
    fn occluded_batch(&self, rays: &[Ray], out: &mut [bool]) {
        for (ray, o) in rays.iter().zip(out.iter_mut()) {
            *o = self.occluded(ray);
        }
    }

    /// Checks that this caster was built from `scene` (as far as it can
    /// tell): called once when the two are put together in a
    /// [`crate::scene::PreparedScene`]. The default accepts any scene.
    ///
    /// # Errors
    /// [`crate::Error::InvalidScene`] naming the mismatch.
    fn check_scene(&self, scene: &Scene) -> Result<()> {
        let _ = scene;
        Ok(())
    }

    /// Whether this caster cuts the holes of the scene's alpha masks
    /// (glTF `alphaMode: MASK`, [`crate::scene::AlphaMask`]): a candidate
    /// hit for which [`Scene::is_hole`] is true is skipped, by
    /// [`intersect`](Self::intersect) (which goes on to what lies behind)
    /// and by [`occluded`](Self::occluded) alike. Embree's scene does
    /// (`crate::embree::HitFilter`). The default, `false`, makes
    /// [`crate::scene::PreparedScene::new`] refuse a scene with holes rather
    /// than trace its cut-outs as walls.
    fn cuts_alpha_masks(&self) -> bool {
        false
    }

    /// The compiled kernels this caster's hits come from, when they depend
    /// on the CPU (Embree's do): photon files record them, and shards traced
    /// with different ones are not merged. The default, `None`, says the
    /// hits do not depend on the CPU.
    fn kernels(&self) -> Option<crate::isa::Kernels> {
        None
    }
}

macro_rules! forward_caster {
    ($($ty:ty),*) => {$(
        impl<C: RayCaster + ?Sized> RayCaster for $ty {
            #[inline]
            fn intersect(&self, ray: &Ray) -> Option<Hit> {
                (**self).intersect(ray)
            }
            #[inline]
            fn occluded(&self, ray: &Ray) -> bool {
                (**self).occluded(ray)
            }
            fn intersect_batch(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
                (**self).intersect_batch(rays, hits)
            }
            fn occluded_batch(&self, rays: &[Ray], out: &mut [bool]) {
                (**self).occluded_batch(rays, out)
            }
            fn check_scene(&self, scene: &Scene) -> Result<()> {
                (**self).check_scene(scene)
            }
            fn kernels(&self) -> Option<crate::isa::Kernels> {
                (**self).kernels()
            }
            fn cuts_alpha_masks(&self) -> bool {
                (**self).cuts_alpha_masks()
            }
        }
    )*};
}

// One Embree scene shared by several prepared scenes (say, the same geometry
// with different light profiles), or a caster behind a trait object.
forward_caster!(&C, Arc<C>, Box<C>);

/// A caster whose every hit is checked against the scene ([`Hit::check`]):
/// the first bad hit is kept and its ray reported as a miss, and
/// [`CheckedCaster::result`] turns it into the error the render ends with.
/// The renderer reads its rays through one, so a caster of the user's that
/// breaks the contract fails the render instead of blackening pixels.
pub(crate) struct CheckedCaster<'a> {
    scene: &'a Scene,
    inner: &'a dyn RayCaster,
    bad: std::sync::OnceLock<BadHit>,
}

impl<'a> CheckedCaster<'a> {
    pub(crate) fn new(scene: &'a Scene, inner: &'a dyn RayCaster) -> Self {
        CheckedCaster {
            scene,
            inner,
            bad: std::sync::OnceLock::new(),
        }
    }

    /// `Ok` unless a hit broke the contract.
    pub(crate) fn result(&self) -> Result<()> {
        match self.bad.get() {
            Some(bad) => Err(bad.into_error(self.scene)),
            None => Ok(()),
        }
    }
}

impl RayCaster for CheckedCaster<'_> {
    #[inline]
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let h = self.inner.intersect(ray)?;
        match h.check(ray, self.scene) {
            Ok(()) => Some(h),
            Err(bad) => {
                let _ = self.bad.set(bad);
                None
            }
        }
    }

    #[inline]
    fn occluded(&self, ray: &Ray) -> bool {
        self.inner.occluded(ray)
    }

    /// The inner caster's batch (its packets), each hit checked as
    /// [`Self::intersect`] checks it.
    fn intersect_batch(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        self.inner.intersect_batch(rays, hits);
        for (ray, hit) in rays.iter().zip(hits.iter_mut()) {
            if let Some(h) = hit {
                if let Err(bad) = h.check(ray, self.scene) {
                    let _ = self.bad.set(bad);
                    *hit = None;
                }
            }
        }
    }

    fn occluded_batch(&self, rays: &[Ray], out: &mut [bool]) {
        self.inner.occluded_batch(rays, out);
    }
}
