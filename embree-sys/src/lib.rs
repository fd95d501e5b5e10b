//! Raw bindings to the system Intel Embree (major 4 or 3, whichever
//! `build.rs` found) and to a small C shim that gives both majors one ray
//! query interface.
//!
//! Nothing here is safe to call without reading Embree's documentation; the
//! safe layer is `adaptive_pm::embree`. What the build found:
//! [`EMBREE_MAJOR`] (also `cfg(embree3)` / `cfg(embree4)` inside this crate)
//! and the metadata `DEP_EMBREE_VERSION_MAJOR` for dependents' build scripts.
//!
//! The ray-query entry points to use are the shim's `apm_intersect1`,
//! `apm_occluded1`, `apm_intersect16` and `apm_occluded16`: they build the
//! per-call context (Embree 3) or arguments (Embree 4) that the header
//! initialises with inline functions, so the same Rust code drives either
//! major. Struct layouts come from the header through bindgen, never from
//! hard-coded sizes (`RTCRayHit` is 80 bytes in Embree 3 and 96 in Embree 4).
#![allow(non_upper_case_globals, non_camel_case_types, non_snake_case)]
#![allow(missing_docs, clippy::all)]

include!(concat!(env!("OUT_DIR"), "/bindings.rs"));

/// `RTC_INVALID_GEOMETRY_ID`, `((unsigned int)-1)` in the header: a cast
/// macro that bindgen does not translate. Marks "no hit" in
/// `RTCHit::geomID` and unused instance-stack slots.
pub const RTC_INVALID_GEOMETRY_ID: u32 = u32::MAX;

/// The Embree major version this crate was built and linked against.
#[cfg(embree4)]
pub const EMBREE_MAJOR: u32 = 4;
/// The Embree major version this crate was built and linked against.
#[cfg(embree3)]
pub const EMBREE_MAJOR: u32 = 3;
