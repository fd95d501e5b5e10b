//! Scenes: a [`SceneBuilder`] that takes triangle meshes and becomes, by
//! value, an immutable [`CommittedScene`] that any number of threads can
//! trace at once.
//!
//! Build settings (documented constants, chosen for a photon tracer that
//! builds once and traces hundreds of millions of rays):
//! - `RTC_BUILD_QUALITY_HIGH` for the scene and every geometry (SAH with
//!   spatial splits: slower build, faster traversal);
//! - `RTC_SCENE_FLAG_ROBUST`: watertight traversal, so photons do not leak
//!   through shared edges of a closed room.
//!
//! Rays that are invalid for Embree (non-finite origin or direction, a
//! coordinate beyond [`EMBREE_LARGE`], zero direction, `tnear < 0`,
//! `tfar < tnear`, NaN) are never passed to it: they miss and are not
//! occluded. Not even in a masked packet lane: Embree 3.13's 8-wide hybrid
//! kernel asserts on every lane it loads (SIGABRT), so a masked lane holds a
//! harmless placeholder ray instead of the invalid one.

use std::ptr::NonNull;
use std::sync::Arc;

use embree_sys as sys;
use glam::Vec3;

use super::device::{Device, DeviceInner};
use super::filter::{self, FilterBox, HitFilter};
use super::packet::BatchKernel;
use super::{Hit, Ray};
use crate::{Error, Result};

// Vertex data is copied as packed `f32` triples into Embree's FLOAT3 buffers.
const _: () = assert!(std::mem::size_of::<Vec3>() == 12 && std::mem::align_of::<Vec3>() == 4);

/// Owns one reference to an Embree scene.
struct SceneHandle(NonNull<sys::RTCSceneTy>);

impl Drop for SceneHandle {
    fn drop(&mut self) {
        // SAFETY: we hold one reference to a live scene and give it back once.
        unsafe { sys::rtcReleaseScene(self.0.as_ptr()) };
    }
}

/// Owns one reference to an Embree geometry (released once attached: the
/// scene keeps its own reference).
struct GeometryHandle(NonNull<sys::RTCGeometryTy>);

impl Drop for GeometryHandle {
    fn drop(&mut self) {
        // SAFETY: we hold one reference to a live geometry and give it back once.
        unsafe { sys::rtcReleaseGeometry(self.0.as_ptr()) };
    }
}

/// A scene under construction. Add meshes, then [`commit`](Self::commit).
pub struct SceneBuilder<'d> {
    device: &'d Device,
    // Field order matters: the scene (and the geometries it holds) is
    // released before the filters they point at.
    scene: SceneHandle,
    /// Material of each geometry, indexed by Embree geometry ID.
    materials: Vec<u32>,
    /// The hit filters of the filtered geometries ([`super::HitFilter`]).
    filters: Vec<FilterBox>,
}

impl std::fmt::Debug for SceneBuilder<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SceneBuilder")
            .field("geometries", &self.materials.len())
            .finish_non_exhaustive()
    }
}

impl Device {
    /// Starts an empty scene on this device.
    ///
    /// # Errors
    /// [`Error::Embree`] when Embree cannot create the scene.
    pub fn scene_builder(&self) -> Result<SceneBuilder<'_>> {
        SceneBuilder::new(self)
    }
}

impl<'d> SceneBuilder<'d> {
    /// Starts an empty scene on `device`.
    ///
    /// # Errors
    /// [`Error::Embree`] when Embree cannot create the scene.
    pub fn new(device: &'d Device) -> Result<Self> {
        let inner = &device.inner;
        let _guard = inner.lock();
        // SAFETY: the device is live; the returned handle is checked for null.
        let raw = unsafe { sys::rtcNewScene(inner.raw()) };
        let scene = SceneHandle(NonNull::new(raw).ok_or_else(|| inner.null_error("rtcNewScene"))?);
        // SAFETY: `scene` is a live scene no other thread can see yet.
        unsafe {
            sys::rtcSetSceneBuildQuality(scene.0.as_ptr(), sys::RTC_BUILD_QUALITY_HIGH);
            sys::rtcSetSceneFlags(scene.0.as_ptr(), sys::RTC_SCENE_FLAG_ROBUST);
        }
        inner.check()?;
        Ok(SceneBuilder {
            device,
            scene,
            materials: Vec::new(),
            filters: Vec::new(),
        })
    }

    /// Adds a triangle mesh whose hits report `material`, and returns its
    /// Embree geometry ID (IDs count up from 0 in the order meshes are added).
    /// The data is copied into buffers Embree owns.
    ///
    /// # Errors
    /// [`Error::InvalidScene`] when the mesh is empty, an index is out of
    /// range, or a position is not finite; [`Error::Embree`] when Embree
    /// fails (out of memory, too many primitives).
    pub fn add_triangles(
        &mut self,
        positions: &[Vec3],
        indices: &[[u32; 3]],
        material: u32,
    ) -> Result<u32> {
        self.add_geometry(positions, indices, material, None)
    }

    /// [`add_triangles`](Self::add_triangles) with a hit filter: every
    /// candidate hit on the mesh, for closest hits and occlusion, single
    /// rays and packets, counts only when `filter(prim_id, u, v)` is true
    /// (`prim_id` indexes `indices`, `u` and `v` are the barycentrics of
    /// its vertices 1 and 2); elsewhere rays pass through. See
    /// [`super::HitFilter`].
    ///
    /// # Errors
    /// As [`add_triangles`](Self::add_triangles); [`Error::Embree`] when
    /// this Embree was built without filter functions.
    pub fn add_triangles_with_filter(
        &mut self,
        positions: &[Vec3],
        indices: &[[u32; 3]],
        material: u32,
        filter: HitFilter,
    ) -> Result<u32> {
        self.add_geometry(positions, indices, material, Some(filter))
    }

    fn add_geometry(
        &mut self,
        positions: &[Vec3],
        indices: &[[u32; 3]],
        material: u32,
        filter: Option<HitFilter>,
    ) -> Result<u32> {
        if indices.is_empty() {
            return Err(Error::InvalidScene("a mesh has no triangles".into()));
        }
        let n_vertices = u32::try_from(positions.len()).map_err(|_| {
            Error::InvalidScene(format!(
                "a mesh has {} vertices, more than u32 indices can address",
                positions.len()
            ))
        })?;
        u32::try_from(indices.len()).map_err(|_| {
            Error::InvalidScene(format!(
                "a mesh has {} triangles, more than Embree accepts",
                indices.len()
            ))
        })?;
        if let Some((i, p)) = positions.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(Error::InvalidScene(format!(
                "vertex {i} is not finite: {p}"
            )));
        }
        if let Some((t, tri)) = indices
            .iter()
            .enumerate()
            .find(|(_, tri)| tri.iter().any(|&i| i >= n_vertices))
        {
            return Err(Error::InvalidScene(format!(
                "triangle {t} has indices {tri:?} but the mesh has {n_vertices} vertices"
            )));
        }

        let inner: &DeviceInner = &self.device.inner;
        let _guard = inner.lock();
        if filter.is_some() && !filter::supported(inner.raw()) {
            return Err(Error::Embree {
                code: 0,
                message: "this Embree was built without filter functions \
                          (EMBREE_FILTER_FUNCTION=OFF): a hit filter (alphaMode MASK) needs them"
                    .into(),
            });
        }
        // SAFETY: the device is live; the handle is checked for null.
        let raw = unsafe { sys::rtcNewGeometry(inner.raw(), sys::RTC_GEOMETRY_TYPE_TRIANGLE) };
        let geometry =
            GeometryHandle(NonNull::new(raw).ok_or_else(|| inner.null_error("rtcNewGeometry"))?);
        let g = geometry.0.as_ptr();
        // The filter goes to `self.filters` before Embree sees it: whatever
        // fails below, it lives as long as the scene that may hold the
        // geometry (field order), and a box's contents never move.
        let filter: Option<*const HitFilter> = filter.map(|f| {
            let b: FilterBox = Box::new(f);
            let at: *const HitFilter = &*b;
            self.filters.push(b);
            at
        });
        // SAFETY: `g` is a live geometry only this thread sees. Embree allocates
        // each buffer for exactly `count` items of `stride` bytes (plus its own
        // padding) and returns null on failure, checked before the copy; the
        // copies write `count * stride` bytes, matching the source slices
        // (`Vec3` and `[u32; 3]` are 12 bytes, checked above).
        unsafe {
            let vertices = sys::rtcSetNewGeometryBuffer(
                g,
                sys::RTC_BUFFER_TYPE_VERTEX,
                0,
                sys::RTC_FORMAT_FLOAT3,
                12,
                positions.len(),
            );
            if vertices.is_null() {
                return Err(inner.null_error("rtcSetNewGeometryBuffer(vertex)"));
            }
            std::ptr::copy_nonoverlapping(
                positions.as_ptr().cast::<u8>(),
                vertices.cast::<u8>(),
                12 * positions.len(),
            );
            let triangles = sys::rtcSetNewGeometryBuffer(
                g,
                sys::RTC_BUFFER_TYPE_INDEX,
                0,
                sys::RTC_FORMAT_UINT3,
                12,
                indices.len(),
            );
            if triangles.is_null() {
                return Err(inner.null_error("rtcSetNewGeometryBuffer(index)"));
            }
            std::ptr::copy_nonoverlapping(
                indices.as_ptr().cast::<u8>(),
                triangles.cast::<u8>(),
                12 * indices.len(),
            );
            sys::rtcSetGeometryBuildQuality(g, sys::RTC_BUILD_QUALITY_HIGH);
            if let Some(f) = filter {
                // `f` is owned by `self.filters`, which outlives the scene
                // holding the geometry (see above and `install`).
                filter::install(g, f);
            }
            sys::rtcCommitGeometry(g);
        }
        inner.check()?;
        // SAFETY: scene and geometry are live and only this thread sees them.
        let geom_id = unsafe { sys::rtcAttachGeometry(self.scene.0.as_ptr(), g) };
        inner.check()?;
        if geom_id == sys::RTC_INVALID_GEOMETRY_ID {
            return Err(inner.null_error("rtcAttachGeometry"));
        }
        let slot = geom_id as usize;
        if self.materials.len() <= slot {
            self.materials.resize(slot + 1, u32::MAX);
        }
        self.materials[slot] = material;
        Ok(geom_id)
    }

    /// Builds the acceleration structure and freezes the scene.
    ///
    /// # Errors
    /// [`Error::Embree`] with the first error Embree reported while building.
    pub fn commit(self) -> Result<CommittedScene> {
        let SceneBuilder {
            device,
            scene,
            materials,
            filters,
        } = self;
        let inner = Arc::clone(&device.inner);
        let bounds = {
            let _guard = inner.lock();
            let mut b = sys::RTCBounds::default();
            // SAFETY: the scene is live and no other thread sees it; `b` is a
            // properly aligned `RTCBounds` for Embree to fill.
            unsafe {
                sys::rtcCommitScene(scene.0.as_ptr());
                sys::rtcGetSceneBounds(scene.0.as_ptr(), &mut b);
            }
            inner.check()?;
            (
                Vec3::new(b.lower_x, b.lower_y, b.lower_z),
                Vec3::new(b.upper_x, b.upper_y, b.upper_z),
            )
        };
        Ok(CommittedScene {
            scene,
            materials,
            bounds,
            device: inner,
            filters,
        })
    }
}

/// A built, immutable scene. Ray queries take `&self` and may run on any
/// number of threads at once.
pub struct CommittedScene {
    // Field order matters: the scene is released before the device reference
    // and before the hit filters its geometries point at.
    scene: SceneHandle,
    materials: Vec<u32>,
    bounds: (Vec3, Vec3),
    device: Arc<DeviceInner>,
    filters: Vec<FilterBox>,
}

// SAFETY: a committed scene is never modified again (no `&mut` methods touch
// Embree); Embree allows `rtcIntersect*` / `rtcOccluded*` on a committed
// scene from any threads concurrently, and its reference counts (released in
// `Drop`, on whatever thread) are atomic. The hit filters Embree calls from
// those threads are `Send + Sync` ([`HitFilter`]).
unsafe impl Send for CommittedScene {}
// SAFETY: see `Send`: shared access only runs the concurrent-safe queries.
unsafe impl Sync for CommittedScene {}

impl std::fmt::Debug for CommittedScene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CommittedScene")
            .field("geometries", &self.materials.len())
            .field("filtered", &self.filters.len())
            .field("bounds", &self.bounds)
            .finish_non_exhaustive()
    }
}

pub use crate::raycast::EMBREE_LARGE;

/// Whether Embree may be given this ray (see the module docs).
#[inline]
pub(crate) fn is_valid(ray: &Ray) -> bool {
    // `abs() <= EMBREE_LARGE` is false for NaN and infinities too.
    let in_range = |v: Vec3| v.abs().cmple(Vec3::splat(EMBREE_LARGE)).all();
    in_range(ray.origin)
        && in_range(ray.dir)
        && ray.dir != Vec3::ZERO
        && ray.tnear >= 0.0
        && ray.tnear <= ray.tfar
}

#[inline]
fn to_rtc_ray(ray: &Ray) -> sys::RTCRay {
    sys::RTCRay {
        org_x: ray.origin.x,
        org_y: ray.origin.y,
        org_z: ray.origin.z,
        tnear: ray.tnear,
        dir_x: ray.dir.x,
        dir_y: ray.dir.y,
        dir_z: ray.dir.z,
        time: 0.0,
        tfar: ray.tfar,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

/// An `RTCRayHit` ready for `rtcIntersect1`.
#[inline]
pub(crate) fn to_rtc_rayhit(ray: &Ray) -> sys::RTCRayHit {
    let mut hit = sys::RTCHit {
        geomID: sys::RTC_INVALID_GEOMETRY_ID,
        primID: sys::RTC_INVALID_GEOMETRY_ID,
        ..Default::default()
    };
    hit.instID.fill(sys::RTC_INVALID_GEOMETRY_ID);
    sys::RTCRayHit {
        ray: to_rtc_ray(ray),
        hit,
    }
}

impl CommittedScene {
    /// The raw scene handle, valid while `self` lives. Only Embree's ray
    /// queries may be called on it (the scene is shared across threads).
    pub fn raw(&self) -> sys::RTCScene {
        self.scene.0.as_ptr()
    }

    /// Number of geometry IDs in use (meshes added).
    pub fn geometry_count(&self) -> usize {
        self.materials.len()
    }

    /// Number of geometries with a hit filter
    /// ([`SceneBuilder::add_triangles_with_filter`]).
    pub fn filtered_count(&self) -> usize {
        self.filters.len()
    }

    /// The material passed to [`SceneBuilder::add_triangles`] for `geom_id`.
    pub fn material(&self, geom_id: u32) -> Option<u32> {
        self.materials.get(geom_id as usize).copied()
    }

    /// Axis-aligned bounds `(lower, upper)` of everything in the scene
    /// (`(+inf, -inf)` componentwise when the scene is empty).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }

    /// The Embree device the scene lives on is kept alive by the scene;
    /// this reports (and clears) its first unchecked error.
    ///
    /// # Errors
    /// That error, as [`Error::Embree`].
    pub fn check(&self) -> Result<()> {
        self.device.check()
    }

    /// The kernel set Embree runs for this scene (its device's).
    pub fn isa(&self) -> Option<crate::isa::Isa> {
        self.device.isa()
    }

    /// Embree's version and kernel set, which the hits depend on.
    pub fn kernels(&self) -> Option<crate::isa::Kernels> {
        let version = self.device.version();
        self.isa().map(|isa| crate::isa::Kernels { isa, version })
    }

    /// The batch kernel of this scene's kernel set: 16-wide packets with
    /// AVX-512 and 8-wide otherwise (every kernel gives the same hits).
    fn batch_kernel(&self) -> BatchKernel {
        BatchKernel::native_for(self.isa())
    }

    /// Converts Embree's answer for one ray.
    #[inline]
    fn hit_from(&self, ray: &sys::RTCRay, hit: &sys::RTCHit) -> Option<Hit> {
        let ng = Vec3::new(hit.Ng_x, hit.Ng_y, hit.Ng_z);
        self.hit(hit.geomID, ray.tfar, ng, hit.primID, hit.u, hit.v)
    }

    /// The [`Hit`] Embree reported (`None` for a miss): the one conversion
    /// behind single rays and packets alike, `ng` unnormalised as Embree
    /// gives it.
    #[inline]
    pub(super) fn hit(
        &self,
        geom_id: u32,
        t: f32,
        ng: Vec3,
        prim_id: u32,
        u: f32,
        v: f32,
    ) -> Option<Hit> {
        if geom_id == sys::RTC_INVALID_GEOMETRY_ID {
            return None;
        }
        Some(Hit {
            t,
            ng: ng.normalize_or_zero(),
            geom_id,
            prim_id,
            u,
            v,
            material: self.material(geom_id).unwrap_or(u32::MAX),
        })
    }

    /// The closest hit along `ray` in `[tnear, tfar]`, if any.
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        if !is_valid(ray) {
            return None;
        }
        let mut rh = to_rtc_rayhit(ray);
        // SAFETY: the scene is committed and alive for `&self`; `rh` is an
        // initialised `RTCRayHit` with the header's layout, exclusively ours.
        unsafe { sys::apm_intersect1(self.raw(), &mut rh) };
        self.hit_from(&rh.ray, &rh.hit)
    }

    /// Whether anything lies along `ray` in `[tnear, tfar]`.
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        if !is_valid(ray) {
            return false;
        }
        let mut r = to_rtc_ray(ray);
        // SAFETY: as in `intersect`, with an initialised `RTCRay`.
        unsafe { sys::apm_occluded1(self.raw(), &mut r) };
        r.tfar == f32::NEG_INFINITY
    }

    /// [`intersect`](Self::intersect) for every ray, in packets as wide as
    /// the device's kernel set. Results are identical to `intersect`'s.
    ///
    /// # Panics
    /// If `rays` and `hits` differ in length.
    pub fn intersect_batch(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        self.intersect_batch_with(self.batch_kernel(), rays, hits);
    }

    /// [`occluded`](Self::occluded) for every ray, in packets as wide as the
    /// device's kernel set.
    ///
    /// # Panics
    /// If `rays` and `out` differ in length.
    pub fn occluded_batch(&self, rays: &[Ray], out: &mut [bool]) {
        self.occluded_batch_with(self.batch_kernel(), rays, out);
    }

    /// [`intersect_batch`](Self::intersect_batch) with a chosen kernel.
    ///
    /// # Panics
    /// If `rays` and `hits` differ in length.
    pub fn intersect_batch_with(
        &self,
        kernel: BatchKernel,
        rays: &[Ray],
        hits: &mut [Option<Hit>],
    ) {
        assert_eq!(
            rays.len(),
            hits.len(),
            "intersect_batch: one hit slot per ray"
        );
        match kernel {
            BatchKernel::Single => {
                for (ray, hit) in rays.iter().zip(hits.iter_mut()) {
                    *hit = self.intersect(ray);
                }
            }
            BatchKernel::Packet8 => self.intersect_packets::<sys::RTCRayHit8>(rays, hits),
            BatchKernel::Packet16 => self.intersect_packets::<sys::RTCRayHit16>(rays, hits),
        }
    }

    /// [`occluded_batch`](Self::occluded_batch) with a chosen kernel.
    ///
    /// # Panics
    /// If `rays` and `out` differ in length.
    pub fn occluded_batch_with(&self, kernel: BatchKernel, rays: &[Ray], out: &mut [bool]) {
        assert_eq!(rays.len(), out.len(), "occluded_batch: one slot per ray");
        match kernel {
            BatchKernel::Single => {
                for (ray, o) in rays.iter().zip(out.iter_mut()) {
                    *o = self.occluded(ray);
                }
            }
            BatchKernel::Packet8 => self.occluded_packets::<sys::RTCRay8>(rays, out),
            BatchKernel::Packet16 => self.occluded_packets::<sys::RTCRay16>(rays, out),
        }
    }
}
