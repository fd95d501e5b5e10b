//! The irradiance cache: irradiance precomputed at a subset of the photons and
//! read by a single nearest-entry lookup (Christensen, "Faster photon map
//! global illumination", JGT 1999).
//!
//! # Build
//! - **Entries**: every `stride`-th photon of the full map in its kd-tree
//!   order. Tree order keeps each leaf's few photons together, so this thins
//!   the photons evenly in space while following their density (where light
//!   is dense, entries are dense). `1 / stride` entries per stored photon.
//! - **Normal**: photons do not store one; a ray cast along the photon's own
//!   direction of travel, from just before its position, finds the surface it
//!   landed on (one ray per entry). An entry whose surface is not found is
//!   dropped.
//! - **Irradiance**: the `k`-nearest estimate of the full map (all depths: the
//!   light leaving a gather hit includes its direct light) with Jensen's cone
//!   filter, counting only photons that arrived on the entry's side *and* lie
//!   in its tangent plane (within [`PLANE_TOLERANCE`] of the scene's
//!   diagonal), so a wall's photons do not leak onto the floor at a corner.
//! - **Storage**: each entry is a 16-byte [`crate::photon_map::CompactPhoton`]
//!   in its own balanced kd-tree: position, irradiance (in the power field,
//!   shared-exponent RGB, 1/512 relative), the reversed normal (in the
//!   direction field), and the estimate's radius as a 6-bit log code (in the
//!   depth field, steps of 2^(1/8)). The cache adds 16 bytes per entry.
//!
//! # Lookup
//! The nearest entry whose normal is within [`NORMAL_COS`] of the query's and
//! whose radius covers the query point. Found: its irradiance. None: the
//! caller falls back to the k-nearest estimate (rare: regions with almost no
//! photons).
//!
//! # Bias
//! On top of the k-nearest estimate's own bias (blur over the radius `r`,
//! and the boundary bias of a disc that runs past a surface's edge), the
//! lookup moves the estimate by up to the distance to the nearest entry,
//! about `r sqrt(pi stride / k)` apart: `0.5 r` at the defaults. Both shrink
//! like `r ~ sqrt(k / N)` as the photon count `N` grows.

use super::estimate::Lookup;
use crate::embree::{CommittedScene, Ray};
use crate::error::{Error, Result};
use crate::photon_map::{Neighbor, PhotonMap, PhotonRecord};
use glam::Vec3;
use rayon::prelude::*;
use std::f32::consts::PI;
use std::time::Instant;

/// Default: one entry per this many photons.
pub const DEFAULT_STRIDE: u32 = 8;
/// Most photons per entry accepted.
pub const MAX_STRIDE: u32 = 1 << 16;
/// Cosine of the largest angle between an entry's normal and the query's.
pub const NORMAL_COS: f32 = 0.9;
/// Photons farther than this fraction of the scene's diagonal from an entry's
/// tangent plane are not counted in its estimate.
pub const PLANE_TOLERANCE: f32 = 1e-3;
/// An entry covers query points within this many times its estimate's radius.
pub const COVER: f32 = 1.0;
/// Radius codes: `r = r_max 2^((code - 63) / 8)`.
const RADIUS_STEPS_PER_OCTAVE: f32 = 8.0;

/// How to build a cache.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CacheConfig {
    /// One entry per `stride` photons (>= 1).
    pub stride: u32,
    /// Photons per irradiance estimate and the largest radius.
    pub lookup: Lookup,
}

impl CacheConfig {
    /// Checks the settings.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the bad setting.
    pub fn validate(&self) -> Result<()> {
        if self.stride == 0 || self.stride > MAX_STRIDE {
            return Err(Error::param(
                "cache stride",
                format!(
                    "must be in 1..={MAX_STRIDE} photons per cache entry, got {}",
                    self.stride
                ),
            ));
        }
        Ok(())
    }
}

/// Irradiance at a subset of the photons, read by one nearest lookup.
pub struct IrradianceCache {
    entries: PhotonMap,
    max_radius: f32,
    /// Seconds to build (normals, estimates, kd-tree).
    pub build_s: f64,
}

fn radius_code(r: f32, max_radius: f32) -> u8 {
    if !(r > 0.0) {
        return 0;
    }
    // Rounded up: the stored radius never under-covers.
    let c = 63.0 + RADIUS_STEPS_PER_OCTAVE * (r / max_radius).log2();
    c.ceil().clamp(0.0, 63.0) as u8
}

fn radius_of(code: u8, max_radius: f32) -> f32 {
    max_radius * ((code as f32 - 63.0) / RADIUS_STEPS_PER_OCTAVE).exp2()
}

impl IrradianceCache {
    /// Builds the cache of `full` (the map of all photons) in the geometry `rt`
    /// whose diagonal is `diagonal`, on the current rayon pool.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a bad configuration.
    pub fn build(
        full: &PhotonMap,
        rt: &CommittedScene,
        diagonal: f32,
        cfg: &CacheConfig,
    ) -> Result<Self> {
        cfg.validate()?;
        let t = Instant::now();
        let stride = cfg.stride as usize;
        let count = full.len().div_ceil(stride);
        let plane = PLANE_TOLERANCE * diagonal;
        let quant = *full.quantizer();
        let max_radius = cfg.lookup.max_radius;
        let records: Vec<PhotonRecord> = (0..count)
            .into_par_iter()
            .map_init(
                || Vec::with_capacity(cfg.lookup.k),
                |scratch, e| {
                    let p = full.photon((e * stride) as u32);
                    let n = surface_normal(rt, p.position, p.direction, diagonal)?;
                    let x = p.position;
                    full.nearest_k_where(x, cfg.lookup.k, max_radius, scratch, |c| {
                        c.direction_unnormalised().dot(n) <= 0.0
                            && (quant.position(c) - x).dot(n).abs() <= plane
                    });
                    let (e, r) = cone_irradiance(full, scratch, cfg.lookup);
                    Some(PhotonRecord {
                        position: x,
                        power: e,
                        direction: -n,
                        depth: radius_code(r, max_radius),
                    })
                },
            )
            .flatten()
            .collect();
        let entries = PhotonMap::build(&records);
        Ok(IrradianceCache {
            entries,
            max_radius,
            build_s: t.elapsed().as_secs_f64(),
        })
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// True when the cache has no entry.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Bytes per entry (the kd-tree's photon size).
    pub fn bytes_per_entry(&self) -> usize {
        self.entries.bytes_per_photon()
    }

    /// The irradiance at `x` (unit normal `n`) from the nearest covering entry.
    pub fn irradiance(&self, x: Vec3, n: Vec3, scratch: &mut Vec<Neighbor>) -> Option<Vec3> {
        let quant = self.entries.quantizer();
        let max_radius = self.max_radius;
        self.entries
            .nearest_k_where(x, 1, max_radius * COVER, scratch, |c| {
                let d = c.direction();
                if -d.dot(n) < NORMAL_COS {
                    return false;
                }
                let r = radius_of(c.depth(), max_radius) * COVER;
                (quant.position(c) - x).length_squared() <= r * r
            });
        scratch.first().map(|nb| self.entries.photon(nb.index).power)
    }
}

/// The cone-filtered irradiance of the neighbours in `scratch` (sorted by
/// distance), and the kernel radius.
fn cone_irradiance(map: &PhotonMap, scratch: &[Neighbor], lookup: Lookup) -> (Vec3, f32) {
    let found = scratch.len();
    if found == 0 {
        return (Vec3::ZERO, lookup.max_radius);
    }
    let r2 = if found >= lookup.k {
        scratch[found - 1].dist2
    } else {
        lookup.max_radius * lookup.max_radius
    };
    let step = map.quantizer().step() as f32;
    let r2 = r2.max(step * step);
    let r = r2.sqrt();
    let mut sum = Vec3::ZERO;
    for nb in scratch {
        let w = (1.0 - nb.dist2.sqrt() / r).max(0.0);
        sum += map.photon(nb.index).power * w;
    }
    (sum * (3.0 / (PI * r2)), r)
}

/// The normal of the surface a photon travelling along `dir` landed on at
/// `p`, facing the photon (against `dir`); `None` when no surface is there.
fn surface_normal(rt: &CommittedScene, p: Vec3, dir: Vec3, diagonal: f32) -> Option<Vec3> {
    let back = 1e-4 * diagonal;
    let ray = Ray {
        tfar: 2.0 * back,
        ..Ray::new(p - dir * back, dir)
    };
    let h = rt.intersect(&ray)?;
    let ng = h.ng.normalize_or_zero();
    let n = if ng.dot(dir) > 0.0 { -ng } else { ng };
    (n != Vec3::ZERO).then_some(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radius_codes_round_up_within_an_eighth_octave() {
        let max = 10.0;
        for r in [0.1f32, 0.37, 1.0, 4.2, 9.99] {
            let back = radius_of(radius_code(r, max), max);
            assert!(back >= r * 0.9999 && back <= r * 1.0905 + 1e-6, "{r} -> {back}");
        }
        assert_eq!(radius_code(20.0, max), 63);
    }
}
