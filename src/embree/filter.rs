//! Hit filters: a safe Rust predicate that Embree asks, for every candidate
//! hit on one geometry, whether the hit counts. A rejected candidate is as
//! if the triangle were not there at that point: the closest-hit query
//! carries on to what lies behind, and the occlusion query does not stop.
//! This is how glTF `alphaMode: MASK` cuts its holes
//! ([`crate::scene::Scene::cutout`] builds the predicate).
//!
//! - One [`HitFilter`] per filtered geometry, installed as both its
//!   intersection and its occlusion filter
//!   (`rtcSetGeometryIntersectFilterFunction`,
//!   `rtcSetGeometryOccludedFilterFunction`), so closest hits, shadow rays,
//!   single rays and 8- and 16-wide packets all skip the same points. A
//!   geometry without a filter costs nothing more than before.
//! - The predicate is called as `filter(prim_id, u, v)` with the
//!   candidate's triangle index in the geometry and Embree's barycentrics of
//!   its vertices 1 and 2, the same `prim_id`, `u` and `v` a [`crate::raycast::Hit`]
//!   reports (`p = (1-u-v) p0 + u p1 + v p2` over the triangle's indices as
//!   they were given to [`super::SceneBuilder::add_triangles_with_filter`]).
//! - Embree calls it on the tracing thread, concurrently from every thread
//!   tracing the scene: it is `Send + Sync` and must not block.
//! - It must not panic: a panic cannot unwind through Embree's C++ frames,
//!   so the callback catches it and aborts the process with a message.
//! - The filter lives in a `Box` owned by the scene (the builder, then the
//!   [`super::CommittedScene`]), which releases its Embree scene, and with
//!   it the geometry that points at the box, before the box is freed.
//!
//! Filters need an Embree built with `EMBREE_FILTER_FUNCTION` (the default,
//! and Debian's and Homebrew's packages); on one without, adding a filtered
//! geometry is refused with [`crate::Error::Embree`] rather than ignored.

use std::ffi::c_void;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Arc;

use embree_sys as sys;

/// Whether a candidate hit at `(prim_id, u, v)` counts (`true`) or is a hole
/// the ray passes through (`false`). See the module docs.
pub type HitFilter = Arc<dyn Fn(u32, f32, f32) -> bool + Send + Sync>;

/// What a filtered geometry's user pointer points at: boxed so that its
/// address is stable for as long as the geometry lives.
pub(super) type FilterBox = Box<HitFilter>;

// The filter reads Embree's `RTCHitN`, a structure of arrays of `N` lanes:
// `Ng_x, Ng_y, Ng_z, u, v, primID, geomID, instID...` (`rtcore_ray.h`:
// `RTCHitN_u(hit, N, i) = ((float*)hit)[3*N+i]`, `RTCHitN_v` at `4*N+i`,
// `RTCHitN_primID` at `5*N+i`; those accessors are C++ only). The 8- and
// 16-wide hit packets are the same layout at fixed N: checked here.
const U_ROW: usize = 3;
const V_ROW: usize = 4;
const PRIM_ROW: usize = 5;
const _: () = {
    assert!(std::mem::offset_of!(sys::RTCHit8, u) == U_ROW * 8 * 4);
    assert!(std::mem::offset_of!(sys::RTCHit8, v) == V_ROW * 8 * 4);
    assert!(std::mem::offset_of!(sys::RTCHit8, primID) == PRIM_ROW * 8 * 4);
    assert!(std::mem::offset_of!(sys::RTCHit16, u) == U_ROW * 16 * 4);
    assert!(std::mem::offset_of!(sys::RTCHit16, v) == V_ROW * 16 * 4);
    assert!(std::mem::offset_of!(sys::RTCHit16, primID) == PRIM_ROW * 16 * 4);
};

/// Embree's filter callback for both queries: asks the geometry's
/// [`HitFilter`] about every valid lane and invalidates (`valid[i] = 0`)
/// the lanes it rejects.
unsafe extern "C" fn filter_hits(args: *const sys::RTCFilterFunctionNArguments) {
    // SAFETY: Embree passes a valid argument block for the duration of the
    // call (`rtcore_geometry.h`, `RTCFilterFunctionNArguments`).
    let args = unsafe { &*args };
    let n = args.N as usize;
    if args.geometryUserPtr.is_null() || args.valid.is_null() || args.hit.is_null() || n == 0 {
        return;
    }
    // SAFETY: the user pointer is the `FilterBox` that `install` registered
    // for this geometry; its owner (the scene builder or committed scene)
    // releases the Embree scene, the only holder of the geometry, before
    // dropping the box, so it is live whenever Embree traces the geometry.
    let filter = unsafe { &*(args.geometryUserPtr as *const HitFilter) };
    // SAFETY: `valid` holds `N` ints that Embree lets the filter write, and
    // nothing else accesses them during the call.
    let valid = unsafe { std::slice::from_raw_parts_mut(args.valid, n) };
    let hit = args.hit as *const u32;
    // SAFETY: `hit` is an `RTCHitN` of `N` lanes (layout checked above):
    // rows of `N` 4-byte values, of which rows 3, 4 and 5 are read at lanes
    // below `N`; all in bounds and initialised by Embree for the candidate.
    let lane = |row: usize, i: usize| unsafe { *hit.add(row * n + i) };
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        for (i, v) in valid.iter_mut().enumerate() {
            if *v == 0 {
                continue;
            }
            let u = f32::from_bits(lane(U_ROW, i));
            let w = f32::from_bits(lane(V_ROW, i));
            if !filter(lane(PRIM_ROW, i), u, w) {
                *v = 0;
            }
        }
    }));
    if outcome.is_err() {
        // Unwinding into Embree is undefined behaviour, and keeping or
        // dropping the hits would be a silently wrong answer.
        eprintln!("adaptive-pm: a hit filter (alpha mask) panicked inside Embree; aborting");
        std::process::abort();
    }
}

/// Whether the device's Embree was built with filter functions.
pub(super) fn supported(device: sys::RTCDevice) -> bool {
    // SAFETY: the device is live; the property exists in Embree 3 and 4.
    unsafe {
        sys::rtcGetDeviceProperty(device, sys::RTC_DEVICE_PROPERTY_FILTER_FUNCTION_SUPPORTED) != 0
    }
}

/// Makes `*filter` the intersection and occlusion filter of `geometry`.
///
/// # Safety
/// `geometry` is a live geometry, not yet committed, that only this thread
/// sees; `filter` points into a [`FilterBox`] that outlives every use of the
/// geometry by Embree (its owner releases the scene holding the geometry
/// before dropping the box).
pub(super) unsafe fn install(geometry: sys::RTCGeometry, filter: *const HitFilter) {
    let user = filter.cast_mut().cast::<c_void>();
    // SAFETY: as the caller guarantees; the callback only reads through the
    // pointer (`&HitFilter`), which `Sync` makes sound from any thread.
    unsafe {
        sys::rtcSetGeometryUserData(geometry, user);
        sys::rtcSetGeometryIntersectFilterFunction(geometry, Some(filter_hits));
        sys::rtcSetGeometryOccludedFilterFunction(geometry, Some(filter_hits));
    }
}
