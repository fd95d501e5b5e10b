//! The irradiance cache: irradiance precomputed at a subset of the photons,
//! averaged into the cells of a hashed grid, read with one hash probe
//! (Christensen, "Faster photon map global illumination", JGT 1999, for the
//! precomputed irradiance; a hashed grid for the O(1) lookup, as LuxCore's
//! PhotonGI and pbrt-v4's SPPM hash their visible points).
//!
//! # Build
//! - **Samples**: the photons whose coin ([`CompactPhoton::content_hash`],
//!   a hash of what the photon carries) comes up one in `stride`: a random
//!   thinning that follows the photons' density.
//! - **Normal**: photons do not store one; a ray cast along the photon's own
//!   direction of travel, from just before its position, finds the surface
//!   it landed on (one ray per sample; a sample whose surface is not found is
//!   dropped).
//! - **Irradiance** at a point: the `k`-nearest estimate of the full map's
//!   photons that are *not* samples, times `stride / (stride - 1)` (all
//!   depths: the light leaving a gather hit includes its direct light), with
//!   Jensen's cone filter, counting only photons that arrived on the sample's
//!   side *and* lie in its tangent plane (within [`PLANE_TOLERANCE`] of the
//!   scene's diagonal), so a wall's photons do not leak onto the floor.
//! - **Cells**: cubes of side `h = r sqrt(4 pi stride / k)` ([`SAMPLES_PER_CELL`]
//!   = 4 samples where the density is the median one; `h = 1.0 r` at the
//!   defaults, `r` the median k-nearest radius of 1024 spread samples), split
//!   by the normal's dominant axis and sign (six buckets: a floor and a wall
//!   meeting in one cube stay apart). A finest cell's value is the estimate
//!   at one of its samples, the one with the least coin (one k-nearest
//!   search per cell, not per sample).
//! - **Levels**: cells of sides `2h` to `16h` ([`LEVELS`]) hold the mean of
//!   the finest cells inside them, each counted once: where photons are
//!   sparse, a lookup reads a coarser cell instead of an empty one.
//! - **Storage**: open addressing, half full: each slot is 8 bytes, a 32-bit
//!   tag of the cell's key and its irradiance in shared-exponent RGB (Ward's
//!   RGBE, 1/256 of the largest channel): **16 bytes per cached cell**
//!   counting the empty slots; cells of all levels ~ 1.3 x the finest's.
//!
//! # Lookup
//! The cell of `x + j` for a jitter `j` uniform in the cube `[-h/2, h/2]^3`
//! (the caller's random numbers), bucket of the query's normal: one hash
//! probe, one or two cache lines. The jitter turns the cells' steps into a
//! tent filter of width `2h` in expectation, so no grid shows in an image; a
//! jitter that lands in an empty cell (past a surface's edge) retries
//! without it, then at the coarser levels; a miss at every level falls back
//! to the k-nearest estimate.
//!
//! # Bias
//! On top of the k-nearest estimate's own bias (blur over its radius `r`,
//! and the boundary bias of a disc that runs past a surface's edge), the
//! cells blur by a tent of width `2h = 2 r` at the defaults, and a cell cut by
//! an edge reads the mean of its part. All of it scales with `r ~ sqrt(k / N)`
//! and vanishes as the photon count `N` grows; a tag collision (two cells
//! with one 32-bit tag on one probe chain, odds ~ cells / 2^32 per lookup)
//! reads a wrong cell.
//!
//! Three biases that would *not* vanish with `N` are removed by construction
//! (each measured before its fix, on the Cornell box at k = 100):
//! - an estimate at a sample that counted the sample's own photon would
//!   have it at distance 0 with the cone's full weight, and read
//!   `(k + 1) / (k - 2)` of the density: +3 % for any `N`;
//! - one that left only that photon out would still count the cell's other
//!   samples, and a cell exists *because* it holds samples: per cell, fewer
//!   other samples lie near its point than near an independent point, and
//!   the estimate read -1.5 %. Estimates therefore count only the photons
//!   that are not samples: an independent thinning of the map, which knows
//!   nothing of which cells exist or which sample each keeps;
//! - a coarse cell holds the mean of its finest cells, each counted once; a
//!   mean over samples would weight its bright part by its photon count.
//!
//! What remains in a finest cell is that its one point is a photon, more
//! likely in its bright part: `|grad E|^2 h^2 / (12 E)`, second order in `h`.

use super::estimate::Lookup;
use crate::embree::{CommittedScene, Ray};
use crate::error::{Error, Result};
use crate::photon_map::{CompactPhoton, Neighbor, PhotonMap};
use crate::rng::mix64;
use glam::Vec3;
use rayon::prelude::*;
use std::f32::consts::PI;
use std::time::Instant;

/// Default: one irradiance sample per this many photons.
pub const DEFAULT_STRIDE: u32 = 8;
/// Fewest photons per sample: estimates count the photons that are not
/// samples (see [Bias](#bias)), so one in one would leave none.
pub const MIN_STRIDE: u32 = 2;
/// Most photons per sample accepted.
pub const MAX_STRIDE: u32 = 1 << 16;
/// Photons farther than this fraction of the scene's diagonal from a
/// sample's tangent plane are not counted in its estimate.
pub const PLANE_TOLERANCE: f32 = 1e-3;
/// Samples expected in a cell where the photon density is the median one:
/// sets the cell side `h = r sqrt(SAMPLES_PER_CELL pi stride / k)` (`r` the
/// median k-nearest radius), so that few cells a surface crosses are empty.
/// 4 rather than 3: a quarter fewer k-nearest searches (the build's whole
/// cost) for the same mean bias at 1e6 photons and up and the same image
/// error (measured with `bench render --fixed-spp 64` at 1e5, 1e6, 1e7).
pub const SAMPLES_PER_CELL: f32 = 4.0;
/// Levels of cells (side `h`, `2h`, ... `16h`): a lookup reads the finest level
/// whose cell holds samples, so where photons are sparse it reads a coarser
/// cell instead of falling back to the k-nearest search.
pub const LEVELS: u32 = 5;

/// How to build a cache.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CacheConfig {
    /// One irradiance sample per `stride` photons (>= 1).
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
        if !(MIN_STRIDE..=MAX_STRIDE).contains(&self.stride) {
            return Err(Error::param(
                "cache stride",
                format!(
                    "must be in {MIN_STRIDE}..={MAX_STRIDE} photons per cache sample, got {}",
                    self.stride
                ),
            ));
        }
        Ok(())
    }
}

/// One slot: a tag of the cell's key (0 = empty) and the irradiance (RGBE).
#[derive(Clone, Copy, Debug, Default)]
struct Slot {
    tag: u32,
    rgbe: u32,
}

/// Irradiance in the cells of a hashed grid, read by one probe.
#[allow(missing_debug_implementations)] // its slots are megabytes of packed cells: nothing useful to print
pub struct IrradianceCache {
    slots: Vec<Slot>,
    origin: Vec3,
    cell: f32,
    inv_cell: f32,
    cells: usize,
    samples: usize,
    /// Seconds to build (normals, estimates, table).
    pub build_s: f64,
}

/// Bucket of a unit normal: dominant axis and sign (0..6).
fn bucket(n: Vec3) -> u64 {
    let a = n.abs();
    let (axis, v) = if a.x >= a.y && a.x >= a.z {
        (0, n.x)
    } else if a.y >= a.z {
        (1, n.y)
    } else {
        (2, n.z)
    };
    axis * 2 + (v < 0.0) as u64
}

/// Ward's RGBE: 8-bit mantissas sharing the largest channel's exponent.
fn to_rgbe(c: Vec3) -> u32 {
    let m = c.max_element();
    if m.is_nan() || m <= 1e-32 || !m.is_finite() {
        return 0;
    }
    let e = m.log2().floor() as i32 + 1;
    let scale = (-e as f32).exp2() * 256.0;
    let q = |x: f32| ((x.max(0.0) * scale) as u32).min(255);
    q(c.x) | (q(c.y) << 8) | (q(c.z) << 16) | (((e + 128).clamp(0, 255) as u32) << 24)
}

fn from_rgbe(v: u32) -> Vec3 {
    if v == 0 {
        return Vec3::ZERO;
    }
    let e = (v >> 24) as i32 - 128;
    let f = ((e - 8) as f32).exp2();
    // Mantissas were truncated: +0.5 centres the error.
    let ch = |s: u32| (((v >> s) & 255) as f32 + 0.5) * f;
    Vec3::new(ch(0), ch(8), ch(16))
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
        let stride = u64::from(cfg.stride);
        let plane = PLANE_TOLERANCE * diagonal;
        let quant = *full.quantizer();
        // A coin per photon, from its content: heads (one in `stride`) makes
        // it a sample, tails a photon that estimates count.
        let is_sample = |c: &CompactPhoton| c.content_hash() % stride == 0;
        // Sample points, their surface normals (one ray each) and coins.
        let samples: Vec<(Vec3, Vec3, u64)> = full
            .compact_photons()
            .par_iter()
            .filter(|c| is_sample(c))
            .filter_map(|c| {
                let p = quant.decode(c);
                let n = surface_normal(rt, p.position, p.direction, diagonal)?;
                Some((p.position, n, c.content_hash()))
            })
            .collect();
        // Estimates count the photons that are not samples, scaled by
        // `stride / (stride - 1)`. Which cells exist, and which sample a cell
        // keeps, depend on the samples; an estimate that counted them would
        // see fewer of them than an independent point does (a cell kept for
        // its one sample has, per cell, fewer others than the Poisson mean)
        // and read low: -3 % at k = 100 without its own photon, +3 % with it,
        // whatever the photon count (both measured). The other photons are an
        // independent thinning of the map, so an estimate from them at any
        // sample is an estimate at an independent point: no bias from the
        // choice of points.
        let scale = stride as f32 / (stride - 1) as f32;
        let estimate = |scratch: &mut Vec<Neighbor>, (x, n, _): (Vec3, Vec3, u64)| {
            full.nearest_k_where(x, cfg.lookup.k, cfg.lookup.max_radius, scratch, |c| {
                !is_sample(c)
                    && c.direction_unnormalised().dot(n) <= 0.0
                    && (quant.position(c) - x).dot(n).abs() <= plane
            });
            let (e, r) = cone_irradiance(full, scratch, cfg.lookup);
            (e * scale, r)
        };
        // The cell side from the median radius of a spread subset of samples.
        let probe_step = (samples.len() / 1024).max(1);
        let mut radii: Vec<f32> = samples
            .par_iter()
            .step_by(probe_step)
            .map_init(
                || Vec::with_capacity(cfg.lookup.k),
                |sc, &s| estimate(sc, s).1,
            )
            .collect();
        let mid = radii.len() / 2;
        let median = if radii.is_empty() {
            cfg.lookup.max_radius
        } else {
            *radii.select_nth_unstable_by(mid, f32::total_cmp).1
        };
        let fraction = (SAMPLES_PER_CELL * PI * cfg.stride as f32 / cfg.lookup.k as f32).sqrt();
        let cell = (fraction * median)
            .max(1e-6 * diagonal)
            .max(f32::MIN_POSITIVE);
        // Cell faces off the round coordinates that walls sit on (a floor at
        // y = 0 on a face would split its samples and lookups by the sign of
        // rounding errors): every level's faces are >= 0.14 h from 0.
        let origin = Vec3::new(0.3127, 0.2718, 0.1414) * cell;
        let mut cache = IrradianceCache {
            slots: Vec::new(),
            origin,
            cell,
            inv_cell: 1.0 / cell,
            cells: 0,
            samples: samples.len(),
            build_s: 0.0,
        };
        // Finest cells: one k-nearest estimate each, at its first sample
        // (keys sorted with the sample index: a fixed choice whatever the
        // thread count).
        let mut fine: Vec<(u64, u32)> = samples
            .iter()
            .enumerate()
            .map(|(i, s)| (cache.key(s.0, s.1, 0), i as u32))
            .collect();
        fine.par_sort_unstable();
        let groups: Vec<&[(u64, u32)]> = fine.chunk_by(|a, b| a.0 == b.0).collect();
        let values: Vec<Vec3> = groups
            .par_iter()
            .map_init(
                || Vec::with_capacity(cfg.lookup.k),
                |sc, g| estimate(sc, samples[Self::pick(&samples, g) as usize]).0,
            )
            .collect();
        // Coarser cells: the mean over the finest cells they hold, each counted
        // once. A mean over samples would weight a cell's bright part by its
        // extra photons (a mean of E weighted by E: too bright by Var E / E).
        let mut keyed: Vec<(u64, u32)> = (1..LEVELS)
            .flat_map(|level| {
                let cache = &cache;
                let samples = &samples;
                groups.iter().enumerate().map(move |(gi, g)| {
                    let s = samples[g[0].1 as usize];
                    (cache.key(s.0, s.1, level), gi as u32)
                })
            })
            .collect();
        keyed.par_sort_unstable();
        let coarse = keyed.chunk_by(|a, b| a.0 == b.0).count();
        let cells = groups.len() + coarse;
        // Half full: 16 bytes per cell with 8-byte slots.
        cache.slots = vec![Slot::default(); (2 * cells).max(2)];
        cache.cells = cells;
        for (g, v) in groups.iter().zip(&values) {
            cache.insert(g[0].0, to_rgbe(*v));
        }
        for group in keyed.chunk_by(|a, b| a.0 == b.0) {
            let sum: Vec3 = group.iter().map(|&(_, gi)| values[gi as usize]).sum();
            cache.insert(group[0].0, to_rgbe(sum / group.len() as f32));
        }
        cache.build_s = t.elapsed().as_secs_f64();
        Ok(cache)
    }

    /// The hashed key of the cell of `x` with normal `n` at `level` (side `h 2^level`).
    fn key(&self, x: Vec3, n: Vec3, level: u32) -> u64 {
        let g = ((x - self.origin) * (self.inv_cell / (1u32 << level) as f32)).floor();
        // Keys wrap every 2^19 cells per axis: far more than any scene we cache.
        let c = |v: f32| (v.clamp(-1e15, 1e15) as i64 as u64) & 0x7_FFFF;
        let meta = bucket(n) | ((level as u64) << 3);
        mix64(c(g.x) | (c(g.y) << 19) | (c(g.z) << 38) | (meta << 57))
    }

    /// The sample whose estimate a finest cell holds: the one of `group`
    /// with the least coin hash, a choice that depends on the samples alone.
    fn pick(samples: &[(Vec3, Vec3, u64)], group: &[(u64, u32)]) -> u32 {
        group
            .iter()
            .map(|&(_, i)| i)
            .min_by_key(|&i| samples[i as usize].2)
            .unwrap_or(group[0].1)
    }

    /// First slot of `key`'s probe chain (multiply-shift onto the table).
    fn home(&self, key: u64) -> usize {
        ((key as u32 as u64 * self.slots.len() as u64) >> 32) as usize
    }

    fn insert(&mut self, key: u64, rgbe: u32) {
        let tag = (key >> 32) as u32 | 1;
        let mut i = self.home(key);
        while self.slots[i].tag != 0 {
            i = if i + 1 == self.slots.len() { 0 } else { i + 1 };
        }
        self.slots[i] = Slot { tag, rgbe };
    }

    fn probe(&self, key: u64) -> Option<Vec3> {
        let tag = (key >> 32) as u32 | 1;
        let mut i = self.home(key);
        loop {
            let s = self.slots.get(i)?;
            if s.tag == tag {
                return Some(from_rgbe(s.rgbe));
            }
            if s.tag == 0 {
                return None;
            }
            i = if i + 1 == self.slots.len() { 0 } else { i + 1 };
        }
    }

    /// Cells holding a value.
    pub fn len(&self) -> usize {
        self.cells
    }

    /// True when the cache has no cell.
    pub fn is_empty(&self) -> bool {
        self.cells == 0
    }

    /// Irradiance samples that went into the cells.
    pub fn samples(&self) -> usize {
        self.samples
    }

    /// Cell side (world units).
    pub fn cell_size(&self) -> f32 {
        self.cell
    }

    /// Bytes per cached cell: the table's bytes over its cells (8-byte slots,
    /// at most half full).
    pub fn bytes_per_entry(&self) -> usize {
        (self.slots.len() * std::mem::size_of::<Slot>()).div_ceil(self.cells.max(1))
    }

    /// The irradiance at `x` (unit normal `n`): at the finest level that has
    /// one, the cell of `x` moved by the jitter `(u - 0.5) h 2^level` (`u` in
    /// `[0, 1)^3`), else the cell of `x` itself.
    pub fn irradiance(&self, x: Vec3, n: Vec3, u: [f32; 3]) -> Option<Vec3> {
        if self.cells == 0 {
            return None;
        }
        let j = (Vec3::from(u) - Vec3::splat(0.5)) * self.cell;
        (0..LEVELS).find_map(|level| {
            let jl = j * (1u32 << level) as f32;
            self.probe(self.key(x + jl, n, level))
                .or_else(|| self.probe(self.key(x, n, level)))
        })
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
    fn rgbe_keeps_three_significant_digits() {
        for c in [
            Vec3::new(1.0, 0.5, 0.25),
            Vec3::new(1e-6, 3e-6, 0.0),
            Vec3::splat(12345.0),
        ] {
            let back = from_rgbe(to_rgbe(c));
            let err = (back - c).abs().max_element() / c.max_element();
            assert!(err <= 1.0 / 256.0 + 1e-6, "{c} -> {back}");
        }
        assert_eq!(from_rgbe(to_rgbe(Vec3::ZERO)), Vec3::ZERO);
    }

    #[test]
    fn buckets_split_the_six_axis_directions() {
        let dirs = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        let mut b: Vec<u64> = dirs.iter().map(|&d| bucket(d)).collect();
        b.sort_unstable();
        b.dedup();
        assert_eq!(b.len(), 6);
    }
}
