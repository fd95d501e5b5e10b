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
//!   in `tests/library/embree_wrapper.rs`).
//! - [`Device::with_isa`]: Embree's kernel set pinned, so that the hits, and
//!   so the photons, do not depend on the CPU ([`crate::isa`]).
//! - Batches: [`CommittedScene::intersect_batch`] uses packets as wide as
//!   the device's kernel set ([`BatchKernel::native_for`]); every
//!   kernel is measured in `benches/rays.rs`.
//! - [`HitFilter`] ([`SceneBuilder::add_triangles_with_filter`]): a safe
//!   predicate Embree's intersection and occlusion filters ask about every
//!   candidate hit on a geometry; rejected points are holes that every ray
//!   passes through (glTF `alphaMode: MASK`, built by
//!   [`crate::scene::Scene::cutout`]). Only filtered geometries pay for it.
//! - [`set_flush_denormals`] / [`thread_pool`]: Embree's traversal expects
//!   flush-to-zero and denormals-are-zero on every tracing thread.
//! - `throughput` (with the `cli` feature, hidden): the measurement behind
//!   `adaptive-pm bench rays`.

mod commit;
mod device;
mod filter;
mod packet;
mod scene;
mod threads;
// The `bench rays` measurement: the command line's, not a library API.
#[cfg(feature = "cli")]
#[doc(hidden)]
pub mod throughput;

pub use commit::EmbreeScene;
pub use device::Device;
pub use filter::HitFilter;
pub use packet::{default_batch_kernel, BatchKernel};
pub use scene::{CommittedScene, SceneBuilder, EMBREE_LARGE};
pub use threads::{
    default_threads, flush_denormals_enabled, max_threads, set_flush_denormals, thread_pool,
    MAX_THREADS_PER_CORE,
};
#[cfg(feature = "cli")]
#[doc(hidden)]
pub use throughput::{measure_throughput, Throughput};

// The ray and hit types are Embree-free (the engine is generic over
// `RayCaster`); re-exported here where they always lived.
pub use crate::raycast::{Hit, Ray};
