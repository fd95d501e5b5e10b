//! The irradiance cache: irradiance precomputed at a subset of the photons,
//! averaged into the cells of a hashed grid, read with one hash probe
//! (Christensen, "Faster photon map global illumination", JGT 1999, for the
//! precomputed irradiance; a hashed grid for the O(1) lookup, as LuxCore's
//! PhotonGI and pbrt-v4's SPPM hash their visible points).
//!
//! # Build
//! - **Samples**: the photons whose coin ([`CompactPhoton::content_hash`](crate::photon_map::CompactPhoton::content_hash),
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
//!   Only photons the sample **sees along its plane** count (`support`'s
//!   `Sight`: 16 rays at the tolerance's height, and between two rays the
//!   nearer of the faces they hit): a floor that runs on under a block or a
//!   partition lends neither its empty part nor the next room's photons.
//!   Divided by the **part of the kernel's disc that it sees on a
//!   surface** within that tolerance (`support`: that sight, and 16 rays
//!   down through the plane at the disc's rim, bisected towards an edge),
//!   not the whole disc: no photon the estimate admits lies past a floor's
//!   end, a wall or a block's top edge, and an estimate that counted that
//!   part read low by it.
//! - **Cells**: cubes of side `h = r sqrt(4 pi stride / k)` ([`SAMPLES_PER_CELL`]
//!   = 4 samples where the density is the median one; `h = 1.0 r` at the
//!   defaults, `r` the median k-nearest radius of 1024 spread samples), split
//!   by the normal's dominant axis and sign (six buckets: a floor and a wall
//!   meeting in one cube stay apart). A finest cell's value is the estimate
//!   at one of its samples, the one with the least coin (one k-nearest
//!   search per cell, not per sample).
//! - **Levels**: cells of sides `2h` to `16h` ([`LEVELS`]) hold the mean of
//!   the finest cells inside them, each counted once: where photons are
//!   sparse, a lookup reads a coarser cell instead of an empty one. A finest
//!   cell's own kernel tells how sparse it is: its *natural* level is the
//!   one whose cells would hold [`SAMPLES_PER_CELL`] samples at its density.
//!   It joins only the levels up to one above it, and a coarse cell averages
//!   only its sparsest members (those of its highest natural level), each
//!   weighted by `1 / P(the cell exists)` (Poisson in its expected samples).
//!   A coarse cell is read where photons are sparse, and one that spans a
//!   wall with the light behind it would otherwise carry the dense, bright
//!   side's cells onto the dark side: on `door` the camera's room read x 4.8
//!   too bright in the image, x 9 on its right wall, which runs on through
//!   the lit room (`render_cache.rs`, `cache_keeps_the_dark_room_dark_on_door`).
//! - **Walls** (`walls`): a cell whose representative (a finest cell's
//!   sample, a coarse cell's member with the least coin) sees a face inside
//!   its cube with surface behind it, or does not see a member it would
//!   average, is *walled*: it averages only the members its representative
//!   sees and keeps the representative's position. A thin wall under a
//!   cell (`door`'s partition under a coarse one) otherwise let a lookup
//!   read the next room's light.
//! - **Storage**: open addressing: each slot is 8 bytes, a 32-bit tag of
//!   the cell's key (one bit of it the walled flag) and its irradiance in
//!   shared-exponent RGB (Ward's RGBE, 1/256 of the largest channel); a
//!   walled cell's position takes a second slot. Two slots a cell: **16
//!   bytes per cached cell** counting the empty slots, the table at most
//!   2/3 full while at most a third of the cells are walled (1 % on the
//!   Cornell box, 3 % on `door`); cells of all levels ~ 1.3 x the finest's.
//!
//! # Lookup
//! The cell of `x + j` for a jitter `j` uniform in the cube `[-h/2, h/2]^3`
//! (the caller's random numbers), bucket of the query's normal: one hash
//! probe, one or two cache lines. The jitter turns the cells' steps into a
//! tent filter of width `2h` in expectation, so no grid shows in an image; a
//! jitter that lands in an empty cell (past a surface's edge) retries
//! without it, then at the coarser levels; a miss at every level falls back
//! to the k-nearest estimate. A walled cell is read only if the lookup's
//! point sees the cell's representative (one segment); else the lookup
//! goes on as on an empty cell.
//!
//! # Bias
//! On top of the k-nearest estimate's own blur over its radius `r`, the
//! cells blur by a tent of width `2h = 2 r` at the defaults, and a cell cut by
//! an edge reads the mean of its part. All of it scales with `r ~ sqrt(k / N)`
//! and vanishes as the photon count `N` grows; a tag collision (two cells
//! with one tag on one probe chain: 30 bits of the key's hash, one bit of
//! the tag forced to 1 and one the walled flag, odds ~ cells / 2^30 per
//! lookup) reads a wrong cell.
//!
//! The boundary bias of a disc that runs past a surface's edge is removed
//! by the kernel share: it scaled with `r` too, and was most of the
//! renderer's bias. On the Cornell box at 256^2 the image's mean read
//! -1.0 to -1.3 % at N_MAX 1e5 and -0.5 to -0.6 % at 3e5 without it,
//! +0.2 to +0.3 % at 1e5 with it (docs/rendering.md, "The kernel's share
//! of the surface"). The k-nearest fallback of a miss (0.07 % of the
//! lookups there) still divides by the whole disc.
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
//! Keeping a coarse cell's sparsest members is a selection: where the
//! density varies within it, they are its darker part. On `door`'s camera
//! room, where nearly every lookup reads a coarse cell, the cache reads
//! 0-12 % below the k-nearest estimate per wall (which itself reads the lit
//! room's photons through the 15 cm partition); on the Cornell box, where
//! the finest cells serve, it matches that estimate within its noise.
//!
//! A lookup read across a wall thinner than its cell before the walled
//! cells: a coarse cell that spanned `door`'s 15 cm partition and held only
//! the lit room's cells was read from the camera's room at the lit room's
//! light (9 times the camera room's at 0.05 kernel radii from the
//! partition, with the lit room 20 times as bright; 1.02 times since:
//! `examples/door_cache_leak.rs`). A wall that clips only a corner of a
//! cube, between the rays that look for walls, can still be missed.
//!
//! What remains in a finest cell is that its one point is a photon, more
//! likely in its bright part: `|grad E|^2 h^2 / (12 E)`, second order in `h`.

use super::estimate::Lookup;
use crate::error::{Error, Result};
use crate::raycast::RayCaster;
use crate::rng::mix64;
use glam::Vec3;
pub use guide::Guide;
use guide::GuideTable;

mod build;
mod guide;
mod sample_estimate;
mod support;
mod walls;

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
/// The level whose cells hold the gather guides (side `8h`: some 64
/// finest cells' photons each, where a finest cell's hundred photons are
/// too few for a histogram of 16 bins that helps). On the Cornell box at
/// N_MAX 1e5, 64 spp, levels 2, 3 and 4 gave 3.06, 3.03 and 3.02 %
/// relRMSE; on `door` at 1e6 (96^2) level 3 gave 30.9 %, level 2 36.2 %
/// (46.2 % with cosine gathers).
const GUIDE_LEVEL: u32 = 3;

/// How to build a cache.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CacheConfig {
    /// One irradiance sample per `stride` photons ([`MIN_STRIDE`] and up).
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

/// One slot: a tag of the cell's key (0 = empty; bit [`WALLED`] set on a
/// walled cell's) and the irradiance (RGBE), or, under [`point_key`], a
/// walled cell's representative position ([`walls::encode`]).
#[derive(Clone, Copy, Debug, Default)]
struct Slot {
    tag: u32,
    payload: u32,
}

/// The tag bit of a cell that a wall crosses ([`walls`]): a lookup reads it
/// only if it sees the cell's representative point.
const WALLED: u32 = 2;

/// A key's tag, without the [`WALLED`] bit, never 0.
fn tag_of(key: u64) -> u32 {
    ((key >> 32) as u32 | 1) & !WALLED
}

/// The key of the slot that holds a walled cell's representative point.
fn point_key(key: u64) -> u64 {
    mix64(key ^ 0x5bd1_e995_c2b2_ae35)
}

/// A cell to read: a point in it, its level and its key.
#[derive(Clone, Copy, Debug)]
struct CellAt {
    at: Vec3,
    level: u32,
    key: u64,
}

/// Irradiance in the cells of a hashed grid, read by one probe.
#[allow(missing_debug_implementations)] // its slots are megabytes of packed cells: nothing useful to print
pub struct IrradianceCache {
    slots: Vec<Slot>,
    origin: Vec3,
    cell: f32,
    inv_cell: f32,
    cells: usize,
    /// Cells that a wall crosses (each holds a second slot, its point).
    walled: usize,
    samples: usize,
    /// How far above a surface the lookups' segments run (the plane
    /// tolerance), world units.
    lift: f32,
    /// The gather guides of the cells of side `8h` ([`guide`]).
    guides: GuideTable,
    /// Seconds to build (normals, estimates, table).
    pub build_s: f64,
}

/// Bucket of a unit normal: dominant axis and sign (0..6).
pub(crate) fn bucket(n: Vec3) -> u64 {
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

/// `floor(v)` clamped to `[-1e15, 1e15]` as an integer (0 for NaN), the
/// cell of a coordinate in cell units: the same value as
/// `v.floor().clamp(-1e15, 1e15) as i64`, without the call to libm's
/// `floorf` that the baseline x86-64 target makes (2 % of a render).
#[inline]
fn cell_index(v: f32) -> i64 {
    // The bounds are integers in f32, so clamping before or after the
    // floor gives the same; `as` truncates towards zero (NaN to 0).
    let t = v.clamp(-1e15, 1e15);
    let i = t as i64;
    i - i64::from((i as f32) > t)
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
    /// The integer coordinates of the cell of `x` at `level` (side `h 2^level`).
    #[inline]
    fn coords(&self, x: Vec3, level: u32) -> [i64; 3] {
        let g = (x - self.origin) * (self.inv_cell / (1u32 << level) as f32);
        [cell_index(g.x), cell_index(g.y), cell_index(g.z)]
    }

    /// The hashed key of the cell of `x` with normal `n` at `level`.
    #[inline]
    fn key(&self, x: Vec3, n: Vec3, level: u32) -> u64 {
        let coords = self.coords(x, level);
        // Keys wrap every 2^19 cells per axis: far more than any scene we cache.
        let c = |i: usize| (coords[i] as u64) & 0x7_FFFF;
        let meta = bucket(n) | ((level as u64) << 3);
        mix64(c(0) | (c(1) << 19) | (c(2) << 38) | (meta << 57))
    }

    /// The cell of `at` with normal `n` at `level`, to read.
    #[inline]
    fn cell_at(&self, at: Vec3, n: Vec3, level: u32) -> CellAt {
        CellAt {
            at,
            level,
            key: self.key(at, n, level),
        }
    }

    /// The low corner and the side of the cube of the cell of `x` at `level`.
    fn cube(&self, x: Vec3, level: u32) -> (Vec3, f32) {
        let side = self.cell * (1u32 << level) as f32;
        let [i, j, k] = self.coords(x, level).map(|i| i as f32);
        (self.origin + Vec3::new(i, j, k) * side, side)
    }

    /// First slot of `key`'s probe chain (multiply-shift onto the table).
    fn home(&self, key: u64) -> usize {
        ((key as u32 as u64 * self.slots.len() as u64) >> 32) as usize
    }

    fn insert(&mut self, key: u64, payload: u32, walled: bool) {
        let tag = tag_of(key) | if walled { WALLED } else { 0 };
        let mut i = self.home(key);
        while self.slots[i].tag != 0 {
            i = if i + 1 == self.slots.len() { 0 } else { i + 1 };
        }
        self.slots[i] = Slot { tag, payload };
    }

    /// The slot of `key`, if any.
    fn probe(&self, key: u64) -> Option<Slot> {
        let tag = tag_of(key);
        let mut i = self.home(key);
        loop {
            let s = *self.slots.get(i)?;
            if s.tag & !WALLED == tag {
                return Some(s);
            }
            if s.tag == 0 {
                return None;
            }
            i = if i + 1 == self.slots.len() { 0 } else { i + 1 };
        }
    }

    /// The irradiance of `cell`, read from `x` (normal `n`): none when the
    /// cell is empty, or walled and `x` does not see its representative
    /// point.
    #[inline]
    fn read(&self, rt: &dyn RayCaster, (x, n): (Vec3, Vec3), cell: &CellAt) -> Option<Vec3> {
        let slot = self.probe(cell.key)?;
        if slot.tag & WALLED != 0 && !self.sees_point(rt, (x, n), cell) {
            return None;
        }
        Some(from_rgbe(slot.payload))
    }

    /// Whether `x` sees the representative point of the walled `cell`
    /// (132 of 10 558 cells on the Cornell box at N_MAX 1e5: kept out of line).
    #[cold]
    #[inline(never)]
    fn sees_point(&self, rt: &dyn RayCaster, (x, n): (Vec3, Vec3), cell: &CellAt) -> bool {
        let Some(point) = self.probe(point_key(cell.key)) else {
            return false;
        };
        let (lo, side) = self.cube(cell.at, cell.level);
        walls::sees(rt, x, n, walls::decode(point.payload, lo, side), self.lift)
    }

    /// Cells holding a value.
    pub fn len(&self) -> usize {
        self.cells
    }

    /// Cells that a wall crosses: a lookup reads one only if it sees the
    /// cell's representative point.
    pub fn walled(&self) -> usize {
        self.walled
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

    /// Where a final gather from the diffuse point `x` (geometric normal
    /// `n`, shading normal `shading`) draws its directions: the guide of
    /// the cell of `x` that holds one, if any ([`Guide`]: a histogram of
    /// the directions its indirect photons came from).
    #[inline]
    pub fn guide(&self, x: Vec3, n: Vec3, shading: Vec3) -> Option<Guide> {
        self.guide_of(self.guide_key(x, n)?, n, shading)
    }

    /// The key of the cell whose guide [`Self::guide`] reads at `x`
    /// (normal `n`); `None` for an empty cache.
    #[inline]
    pub(crate) fn guide_key(&self, x: Vec3, n: Vec3) -> Option<u64> {
        (self.cells > 0).then(|| self.key(x, n, GUIDE_LEVEL))
    }

    /// [`Self::guide`] of the cell `key` ([`Self::guide_key`]).
    pub(crate) fn guide_of(&self, key: u64, n: Vec3, shading: Vec3) -> Option<Guide> {
        let h = self.guides.get(key)?;
        Some(h.guide(guide::frame(n, shading)))
    }

    /// Cells (of side `8h`) that hold a gather guide.
    pub fn guides(&self) -> usize {
        self.guides.len()
    }

    /// Bytes of the gather guides' table (beside the cells' 16 a cell).
    pub fn guide_bytes(&self) -> usize {
        self.guides.bytes()
    }

    /// Bytes per cached cell: the table's bytes over its cells (8-byte slots,
    /// at most half full; a walled cell takes a second slot for its point).
    pub fn bytes_per_entry(&self) -> usize {
        (self.slots.len() * std::mem::size_of::<Slot>()).div_ceil(self.cells.max(1))
    }

    /// The irradiance at `x` (unit normal `n`): at the finest level that has
    /// one, the cell of `x` moved by the jitter `(u - 0.5) h 2^level` (`u` in
    /// `[0, 1)^3`), else the cell of `x` itself. A cell that a wall crosses
    /// is read only if `x` sees its representative point (one segment cast
    /// by `rt`, the caster of the scene the cache was built in).
    pub fn irradiance(&self, x: Vec3, n: Vec3, u: [f32; 3], rt: &dyn RayCaster) -> Option<Vec3> {
        if self.cells == 0 {
            return None;
        }
        let j = (Vec3::from(u) - Vec3::splat(0.5)) * self.cell;
        (0..LEVELS).find_map(|level| {
            let jittered = self.cell_at(x + j * (1u32 << level) as f32, n, level);
            self.read(rt, (x, n), &jittered).or_else(|| {
                let own = self.cell_at(x, n, level);
                (own.key != jittered.key)
                    .then(|| self.read(rt, (x, n), &own))
                    .flatten()
            })
        })
    }
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
    fn cell_index_is_the_clamped_floor() {
        let reference = |v: f32| v.floor().clamp(-1e15, 1e15) as i64;
        let mut r = crate::rng::Rng::new(4);
        let special = [
            0.0f32,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            1e-30,
            -1e-30,
            8_388_607.5,
            -8_388_607.5,
            16_777_217.0,
            1e15,
            -1e15,
            2e15,
            -2e15,
            1e20,
            -1e20,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        let spread =
            (0..100_000).map(|_| (r.next_f32() - 0.5) * 2f32.powi((r.next_f32() * 60.0) as i32));
        for v in special.into_iter().chain(spread) {
            assert_eq!(cell_index(v), reference(v), "{v}");
        }
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
