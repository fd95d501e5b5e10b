//! The safe face of Embree: devices, scenes, rays and hits, and the thread
//! setup ray tracing wants. This module (with `embree-sys`) holds the
//! crate's only `unsafe` code; every block says why it is sound.
//!
//! - [`Device`]: RAII handle; Embree errors arrive through its callback and
//!   come out as [`crate::Error::Embree`] at the next check (scene creation,
//!   geometry upload, commit), never per ray.
//! - [`SceneBuilder`] → [`CommittedScene`] by value (`commit(self)`): the
//!   committed scene is `Send + Sync` and traced concurrently through `&self`.
//! - [`Ray`] / [`Hit`]: plain `Copy` data; the hit normal is Embree's
//!   geometric normal normalised, *not* flipped toward the ray: it is
//!   `normalize((v1 - v0) x (v2 - v0))`, counter-clockwise winding (checked
//!   in `tests/embree_wrapper.rs`).
//! - Batches: [`CommittedScene::intersect_batch`] uses
//!   [`DEFAULT_BATCH_KERNEL`]; both kernels are measured in `benches/rays.rs`.
//! - [`set_flush_denormals`] / [`thread_pool`]: Embree's traversal expects
//!   flush-to-zero and denormals-are-zero on every tracing thread.
//! - `throughput` (with the `cli` feature, hidden): the measurement behind
//!   `adaptive-pm bench rays`.

mod device;
mod scene;
mod threads;
// The `bench rays` measurement: the command line's, not a library API.
#[cfg(feature = "cli")]
#[doc(hidden)]
pub mod throughput;

use glam::Vec3;

pub use device::Device;
pub use scene::{BatchKernel, CommittedScene, SceneBuilder, DEFAULT_BATCH_KERNEL, EMBREE_LARGE};
pub use threads::{flush_denormals_enabled, set_flush_denormals, thread_pool};
#[cfg(feature = "cli")]
#[doc(hidden)]
pub use throughput::{measure_throughput, Throughput};

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
    /// Unit geometric normal as Embree reports it (not flipped toward the ray).
    pub ng: Vec3,
    /// Geometry ID returned by [`SceneBuilder::add_triangles`].
    pub geom_id: u32,
    /// Triangle index within that geometry.
    pub prim_id: u32,
    /// Barycentric coordinate of vertex 1 (`p = (1-u-v) p0 + u p1 + v p2`).
    pub u: f32,
    /// Barycentric coordinate of vertex 2.
    pub v: f32,
    /// The material given with the geometry.
    pub material: u32,
}
