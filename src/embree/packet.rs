//! Ray packets: 8- and 16-wide, one generic route from [`Ray`]s to Embree's
//! structure-of-arrays packets and back to [`Hit`]s.
//!
//! Embree's native packet is as wide as the CPU's vectors: 16 with AVX-512,
//! 8 with AVX2, where a 16-wide packet is traced as two 8-wide halves with
//! some overhead. On the AVX2 machines of this project the 16-wide call
//! measured about 10 % slower than one 8-wide call per 8 rays (a C loop over
//! the same rays, robust scene); [`default_batch_kernel`] picks the width.

use embree_sys as sys;
use glam::Vec3;

use super::scene::{is_valid, CommittedScene};
use super::{Hit, Ray};

/// How a batch of rays is handed to Embree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BatchKernel {
    /// One `rtcIntersect1` / `rtcOccluded1` call per ray.
    Single,
    /// 8-ray packets (`rtcIntersect8` / `rtcOccluded8`).
    Packet8,
    /// 16-ray packets (`rtcIntersect16` / `rtcOccluded16`).
    Packet16,
}

/// The kernel [`CommittedScene::intersect_batch`] and
/// [`CommittedScene::occluded_batch`] use on a device of the CPU's widest
/// kernel set: packets of the CPU's native width, 16 with AVX-512 and 8
/// otherwise (a pinned set picks its own width, [`BatchKernel::native_for`]). Every kernel gives bit-identical results
/// (`tests/library/embree_wrapper.rs`), so the choice changes speed only.
///
/// Measured: 16-wide packets were 1.1-1.25x faster than single-ray calls on
/// an AVX-512 CPU (`benches/rays.rs`), and on AVX2 about 10 % slower than
/// single calls or 8-wide packets (module docs).
pub fn default_batch_kernel() -> BatchKernel {
    BatchKernel::native_for(crate::isa::Isa::native())
}

impl BatchKernel {
    /// The packets native to Embree's kernel set `isa`: 16-wide for AVX-512,
    /// 8-wide otherwise.
    pub fn native_for(isa: Option<crate::isa::Isa>) -> BatchKernel {
        match isa {
            Some(crate::isa::Isa::Avx512) => BatchKernel::Packet16,
            _ => BatchKernel::Packet8,
        }
    }
}

/// Embree's validity mask (`-1` active, `0` inactive), 64-byte aligned as
/// `rtcIntersect16` requires (8-wide calls read the first 8 lanes and need
/// 32 bytes).
#[repr(C, align(64))]
pub(super) struct ValidMask([i32; 16]);

/// The ray lanes of a packet.
pub(super) trait RayLanes: Default {
    const WIDTH: usize;
    fn set(&mut self, lane: usize, r: &Ray);
    /// After an occlusion query: whether the lane's ray was occluded.
    fn occluded(&self, lane: usize) -> bool;
    /// Occlusion query of the active lanes.
    ///
    /// # Safety
    /// `scene` is a committed scene alive for the call.
    unsafe fn trace(&mut self, valid: &ValidMask, scene: sys::RTCScene);
}

/// A packet of rays and their hits.
pub(super) trait HitLanes: Default {
    type Rays: RayLanes;
    fn rays(&mut self) -> &mut Self::Rays;
    /// Marks every lane as a miss (Embree writes only the lanes it hits).
    fn clear_hits(&mut self);
    /// `(geom_id, t, unnormalised Ng, prim_id, u, v)` of a lane.
    fn lane(&self, lane: usize) -> (u32, f32, Vec3, u32, f32, f32);
    /// Closest-hit query of the active lanes.
    ///
    /// # Safety
    /// `scene` is a committed scene alive for the call.
    unsafe fn trace(&mut self, valid: &ValidMask, scene: sys::RTCScene);
}

macro_rules! packet_layout {
    ($width:literal, $Ray:ident, $RayHit:ident, $intersect:ident, $occluded:ident) => {
        impl RayLanes for sys::$Ray {
            const WIDTH: usize = $width;

            #[inline]
            fn set(&mut self, lane: usize, r: &Ray) {
                self.org_x[lane] = r.origin.x;
                self.org_y[lane] = r.origin.y;
                self.org_z[lane] = r.origin.z;
                self.tnear[lane] = r.tnear;
                self.dir_x[lane] = r.dir.x;
                self.dir_y[lane] = r.dir.y;
                self.dir_z[lane] = r.dir.z;
                self.time[lane] = 0.0;
                self.tfar[lane] = r.tfar;
                self.mask[lane] = u32::MAX;
                self.id[lane] = 0;
                self.flags[lane] = 0;
            }

            #[inline]
            fn occluded(&self, lane: usize) -> bool {
                self.tfar[lane] == f32::NEG_INFINITY
            }

            #[inline]
            unsafe fn trace(&mut self, valid: &ValidMask, scene: sys::RTCScene) {
                // SAFETY: the caller passes a live committed scene; `valid`
                // and `self` are initialised, aligned as Embree requires
                // (their types' `align` attributes) and exclusively ours.
                unsafe { sys::$occluded(valid.0.as_ptr(), scene, self) };
            }
        }

        impl HitLanes for sys::$RayHit {
            type Rays = sys::$Ray;

            #[inline]
            fn rays(&mut self) -> &mut sys::$Ray {
                &mut self.ray
            }

            #[inline]
            fn clear_hits(&mut self) {
                self.hit.geomID = [sys::RTC_INVALID_GEOMETRY_ID; $width];
            }

            #[inline]
            fn lane(&self, l: usize) -> (u32, f32, Vec3, u32, f32, f32) {
                let h = &self.hit;
                let ng = Vec3::new(h.Ng_x[l], h.Ng_y[l], h.Ng_z[l]);
                (
                    h.geomID[l],
                    self.ray.tfar[l],
                    ng,
                    h.primID[l],
                    h.u[l],
                    h.v[l],
                )
            }

            #[inline]
            unsafe fn trace(&mut self, valid: &ValidMask, scene: sys::RTCScene) {
                // SAFETY: as for the ray lanes above.
                unsafe { sys::$intersect(valid.0.as_ptr(), scene, self) };
            }
        }
    };
}

packet_layout!(8, RTCRay8, RTCRayHit8, apm_intersect8, apm_occluded8);
packet_layout!(16, RTCRay16, RTCRayHit16, apm_intersect16, apm_occluded16);

/// Fills a packet's rays; lanes past `rays.len()` or holding an invalid ray
/// are masked off.
#[inline]
fn fill<P: RayLanes>(rays: &[Ray], p: &mut P, valid: &mut ValidMask) {
    for lane in 0..P::WIDTH {
        // An invalid ray is replaced, not only masked (see the scene module's docs).
        let r = rays.get(lane).copied().filter(is_valid);
        valid.0[lane] = if r.is_some() { -1 } else { 0 };
        p.set(lane, &r.unwrap_or_else(|| Ray::new(Vec3::ZERO, Vec3::Z)));
    }
}

impl CommittedScene {
    /// Closest hits of `rays` in packets of `P`'s width.
    pub(super) fn intersect_packets<P: HitLanes>(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        let mut packet = P::default();
        let mut valid = ValidMask([0; 16]);
        let width = P::Rays::WIDTH;
        for (rays, hits) in rays.chunks(width).zip(hits.chunks_mut(width)) {
            fill(rays, packet.rays(), &mut valid);
            packet.clear_hits();
            // SAFETY: `self` is committed and alive for the borrow.
            unsafe { packet.trace(&valid, self.raw()) };
            for (lane, hit) in hits.iter_mut().enumerate() {
                let (geom_id, t, ng, prim_id, u, v) = packet.lane(lane);
                *hit = if valid.0[lane] == 0 {
                    None
                } else {
                    self.hit(geom_id, t, ng, prim_id, u, v)
                };
            }
        }
    }

    /// Occlusion of `rays` in packets of `P`'s width.
    pub(super) fn occluded_packets<P: RayLanes>(&self, rays: &[Ray], out: &mut [bool]) {
        let mut packet = P::default();
        let mut valid = ValidMask([0; 16]);
        for (rays, out) in rays.chunks(P::WIDTH).zip(out.chunks_mut(P::WIDTH)) {
            fill(rays, &mut packet, &mut valid);
            // SAFETY: `self` is committed and alive for the borrow.
            unsafe { packet.trace(&valid, self.raw()) };
            for (lane, o) in out.iter_mut().enumerate() {
                *o = valid.0[lane] != 0 && packet.occluded(lane);
            }
        }
    }
}
