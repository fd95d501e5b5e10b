//! The importance pass's cells and their exact fixed-point sums, while the
//! pass runs and when shards merge ([`ImportanceSums`]); frozen into the
//! lookup table by [`super::table`]. See the module docs of [`super`] for
//! the cell rule.

use crate::error::{Error, Result};
use crate::render::cache::bucket;
use glam::Vec3;
use std::collections::HashMap;

/// One unit of throughput in the fixed-point sums: 2^24, so a deposit is
/// kept to 6e-8 of a camera sample's throughput.
pub const FIXED_ONE: f64 = 16_777_216.0;
/// The largest deposit counted, in throughput units (a glossy weight or a
/// grazing glass path can exceed 1; far above is a numerical accident): a
/// cell overflows its u64 only after 2^24 such deposits.
pub const MAX_DEPOSIT: f64 = 65_536.0;
/// The readers kept apart in the sums: first hits, gather hits, later
/// bounces (the camera walk's `Reader` order).
pub const READERS: usize = 3;

/// Bits of a cell coordinate in a key: coordinates wrap every 2^19 cells
/// per axis, far beyond the 1/fraction cells a scene's diagonal spans.
const COORD_BITS: u32 = 19;
const COORD_MASK: u64 = (1 << COORD_BITS) - 1;
/// The level bit of a coarse (adjoint) cell's key.
const COARSE: u64 = 1 << 60;

/// The adjoint's cells are this many cells a side: later bounces spread
/// their deposits thin, and 16 times the area per cell averages them (the
/// alpha_I they set would otherwise be noise, most cells of a room seen
/// only through a door holding no deposit at all).
pub const ADJOINT_COARSENING: i64 = 4;

/// A throughput as a fixed-point deposit (0 for NaN, negative or zero).
pub(crate) fn to_fixed(w: f32) -> u64 {
    let w = f64::from(w);
    if w > 0.0 {
        (w.min(MAX_DEPOSIT) * FIXED_ONE).round() as u64
    } else {
        0
    }
}

/// Where cells are: cubes of side `cell` from `origin`, each split into six
/// buckets by the dominant axis and sign of the normal on the side the ray
/// arrived from (a wall's two faces, and a floor and a wall meeting in one
/// cube, are different cells).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellGrid {
    origin: Vec3,
    cell: f32,
    reach: f32,
}

/// The bucket bits of a reach cell's key: no normal's bucket (those are
/// 0..6), since the store rule holds for photons on surfaces of any side.
const ANY_SIDE: u64 = 7;

/// The most reach cells a read cell's flag spreads over, per axis and
/// side: beyond, [`CellGrid::reach_cells`] is `None` and every photon is
/// stored (a radius that wide reads nearly the whole scene anyway).
pub const MAX_REACH_CELLS: i64 = 4;

impl CellGrid {
    /// Cells of side `fraction` times the diagonal of the box `lo..hi`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a fraction outside `(0, 1]`, or a
    /// box whose diagonal is not a positive finite number.
    pub fn for_bounds(lo: Vec3, hi: Vec3, fraction: f32) -> Result<Self> {
        if !(fraction > 0.0 && fraction <= 1.0) {
            return Err(Error::param(
                "importance cell",
                format!("the cell fraction of the diagonal must be in (0, 1], got {fraction}"),
            ));
        }
        let diagonal = (hi - lo).length();
        if !(diagonal.is_finite() && diagonal > 0.0) {
            return Err(Error::param(
                "importance cell",
                "the scene's bounds have no positive finite diagonal",
            ));
        }
        Ok(CellGrid {
            origin: lo,
            cell: diagonal * fraction,
            reach: diagonal * crate::render::DEFAULT_MAX_RADIUS_FRACTION,
        })
    }

    /// The same cells for a render whose kernels reach `reach` (world
    /// units; [`CellGrid::for_bounds`] takes the renderer's default, a
    /// tenth of the diagonal): photons within it of a read point are
    /// stored.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a reach that is not a positive
    /// finite number.
    pub fn with_reach(self, reach: f32) -> Result<Self> {
        if !(reach.is_finite() && reach > 0.0) {
            return Err(Error::param(
                "importance reach",
                format!("the kernel radius must be a positive finite length, got {reach}"),
            ));
        }
        Ok(CellGrid { reach, ..self })
    }

    /// The largest kernel radius the store rule covers (world units).
    pub fn reach(&self) -> f32 {
        self.reach
    }

    /// How many reach cells (the adjoint's coarse cubes, side
    /// [`ADJOINT_COARSENING`] cells) a read cell's store flag spreads over
    /// on each side: enough that every point within [`CellGrid::reach`] of
    /// a read point lies in a flagged cube. `None` beyond
    /// [`MAX_REACH_CELLS`]: store everywhere.
    pub fn reach_cells(&self) -> Option<i64> {
        let side = self.cell * ADJOINT_COARSENING as f32;
        let d = (self.reach / side).ceil();
        (d <= MAX_REACH_CELLS as f32).then_some(d.max(1.0) as i64)
    }

    /// The key of the reach cube of `x`: the coarse cube, on no side.
    pub fn reach_key(&self, x: Vec3) -> u64 {
        Self::reach_of(self.coarse_key(x, Vec3::Y))
    }

    /// The reach cube of the cell or coarse cell `key`.
    pub(super) fn reach_of(key: u64) -> u64 {
        let coarse = if key & COARSE != 0 {
            key
        } else {
            Self::coarse_of(key)
        };
        (coarse & !(7 << 57)) | (ANY_SIDE << 57)
    }

    /// The side of a cell (world units).
    pub fn cell_size(&self) -> f32 {
        self.cell
    }

    /// The key of the cell of point `x` seen from the side of unit normal
    /// `n`: three wrapped coordinates and the normal's bucket, packed.
    pub fn key(&self, x: Vec3, n: Vec3) -> u64 {
        let g = ((x - self.origin) / self.cell).floor();
        let c = |v: f32| (v.clamp(-1e15, 1e15) as i64 as u64) & COORD_MASK;
        c(g.x) | (c(g.y) << COORD_BITS) | (c(g.z) << (2 * COORD_BITS)) | (bucket(n) << 57)
    }

    /// The key of the adjoint's coarse cell of `x` (side
    /// [`ADJOINT_COARSENING`] cells) seen from the side of `n`.
    pub fn coarse_key(&self, x: Vec3, n: Vec3) -> u64 {
        let side = self.cell * ADJOINT_COARSENING as f32;
        let g = ((x - self.origin) / side).floor();
        let c = |v: f32| (v.clamp(-1e15, 1e15) as i64 as u64) & COORD_MASK;
        let xyz = c(g.x) | (c(g.y) << COORD_BITS) | (c(g.z) << (2 * COORD_BITS));
        xyz | (bucket(n) << 57) | COARSE
    }

    /// The coarse key of the cell `key` (the same as [`CellGrid::coarse_key`]
    /// of its points: scaling by 4 commutes with rounding).
    pub(super) fn coarse_of(key: u64) -> u64 {
        let signed = |i: u32| {
            let v = ((key >> (i * COORD_BITS)) & COORD_MASK) as i64;
            if v >= 1 << (COORD_BITS - 1) {
                v - (1 << COORD_BITS)
            } else {
                v
            }
        };
        let c = |i: u32| (signed(i).div_euclid(ADJOINT_COARSENING) as u64) & COORD_MASK;
        let xyz = c(0) | (c(1) << COORD_BITS) | (c(2) << (2 * COORD_BITS));
        xyz | (key & (7 << 57)) | COARSE
    }

    /// The `(2 d + 1)^3` cells around `key`'s and itself, on its level and
    /// side.
    pub(super) fn around(key: u64, d: i64) -> impl Iterator<Item = u64> {
        let field = |i: u32| (key >> (i * COORD_BITS)) & COORD_MASK;
        let (x, y, z, rest) = (field(0), field(1), field(2), key >> 57);
        let step = |v: u64, o: i64| (v as i64 + o) as u64 & COORD_MASK;
        let w = 2 * d + 1;
        (0..w * w * w).map(move |i| {
            let (dx, dy, dz) = (i % w - d, i / w % w - d, i / (w * w) - d);
            step(x, dx)
                | (step(y, dy) << COORD_BITS)
                | (step(z, dz) << (2 * COORD_BITS))
                | (rest << 57)
        })
    }
}

/// Per-cell fixed-point sums of a pass or a shard of it, sorted by key.
/// Integer sums do not depend on the order of the deposits: merging the
/// shards of a pass gives bitwise the whole pass's sums.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportanceSums {
    pub(crate) grid: CellGrid,
    /// Camera samples of the whole pass (every shard's), the sums' divisor.
    pub(crate) samples: u64,
    pub(crate) cells: Vec<(u64, [u64; READERS])>,
}

/// Deposits of part of a pass, in any order.
#[derive(Default)]
pub(crate) struct Accumulator {
    map: HashMap<u64, [u64; READERS]>,
}

impl Accumulator {
    pub(crate) fn add(&mut self, key: u64, reader: usize, fixed: u64) {
        if fixed > 0 {
            let c = self.map.entry(key).or_default();
            c[reader] = c[reader].saturating_add(fixed);
        }
    }

    /// Both parts' deposits (saturating sums of non-negative terms: the
    /// same whatever the order).
    pub(crate) fn merge(mut self, other: Accumulator) -> Accumulator {
        let (mut big, small) = if self.map.len() >= other.map.len() {
            (std::mem::take(&mut self.map), other.map)
        } else {
            (other.map, std::mem::take(&mut self.map))
        };
        for (k, v) in small {
            let c = big.entry(k).or_default();
            for r in 0..READERS {
                c[r] = c[r].saturating_add(v[r]);
            }
        }
        Accumulator { map: big }
    }

    pub(crate) fn into_sums(self, grid: CellGrid, samples: u64) -> ImportanceSums {
        let mut cells: Vec<_> = self.map.into_iter().collect();
        cells.sort_unstable_by_key(|&(k, _)| k);
        ImportanceSums {
            grid,
            samples,
            cells,
        }
    }
}

impl ImportanceSums {
    /// The sums of the shards of one pass, merged: bitwise the whole pass's.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for no part, or parts of passes with
    /// other cells or sample counts.
    pub fn merge(parts: &[ImportanceSums]) -> Result<Self> {
        let first = parts
            .first()
            .ok_or_else(|| Error::param("importance", "nothing to merge"))?;
        let mut acc = Accumulator::default();
        for p in parts {
            if p.grid != first.grid || p.samples != first.samples {
                return Err(Error::param(
                    "importance",
                    "the parts come from passes with other cells or sample counts",
                ));
            }
            let mut part = Accumulator::default();
            for &(k, v) in &p.cells {
                for (r, &f) in v.iter().enumerate() {
                    part.add(k, r, f);
                }
            }
            acc = acc.merge(part);
        }
        Ok(acc.into_sums(first.grid, first.samples))
    }

    /// The cells' geometry.
    pub fn grid(&self) -> CellGrid {
        self.grid
    }

    /// Camera samples of the whole pass.
    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// The cells, sorted by key: each key and its fixed-point sums by reader.
    pub fn cells(&self) -> &[(u64, [u64; READERS])] {
        &self.cells
    }

    /// The throughput reader `reader` received over all cells, per camera
    /// sample (the first hits': the share of samples that hit a surface).
    pub fn total_per_sample(&self, reader: usize) -> f64 {
        let sum: u128 = self.cells.iter().map(|c| u128::from(c.1[reader])).sum();
        sum as f64 / FIXED_ONE / self.samples.max(1) as f64
    }

    /// Importance per unit area and camera sample of a cell's sums for
    /// reader `reader`: its throughput over the samples and `cell^2` (the
    /// area a flat surface along a grid plane has in a cell).
    pub fn density(&self, sums: &[u64; READERS], reader: usize) -> f64 {
        let h = f64::from(self.grid.cell);
        sums[reader] as f64 / FIXED_ONE / (self.samples.max(1) as f64 * h * h)
    }

    /// The lookup table of these sums.
    pub fn freeze(&self) -> super::ImportanceGrid {
        super::ImportanceGrid::from_sums(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn around_is_the_cube_of_cells_in_the_bucket() {
        let g = CellGrid::for_bounds(Vec3::ZERO, Vec3::ONE, 0.1).unwrap();
        let key = g.key(Vec3::splat(0.05), Vec3::Y);
        let mut n: Vec<u64> = CellGrid::around(key, 1).collect();
        n.sort_unstable();
        n.dedup();
        assert_eq!(n.len(), 27);
        assert!(n.contains(&key));
        let h = g.cell_size();
        assert!(n.contains(&g.key(Vec3::splat(0.05) + Vec3::new(h, -h, 0.0), Vec3::Y)));
        assert!(!n.contains(&g.key(Vec3::splat(0.05) + Vec3::X * h, -Vec3::Y)));
        assert_eq!(CellGrid::around(key, 2).count(), 125);
    }

    #[test]
    fn the_reach_cubes_cover_every_point_within_the_reach() {
        // Cells of 1/64 of the diagonal: reach cubes of 1/16, a reach of a
        // tenth of the diagonal spreads two cubes a side.
        let g = CellGrid::for_bounds(Vec3::ZERO, Vec3::ONE, 1.0 / 64.0).unwrap();
        let d = g.reach_cells().unwrap();
        assert_eq!(d, 2);
        let mut rng = crate::rng::Rng::new(7);
        for _ in 0..2000 {
            let p = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            let dir = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5;
            let q = p + dir.normalize_or_zero() * g.reach() * rng.next_f32();
            let near: Vec<u64> =
                CellGrid::around(CellGrid::reach_of(g.key(p, Vec3::Y)), d).collect();
            assert!(near.contains(&g.reach_key(q)), "{p} -> {q}");
        }
        let wide = g.with_reach(1.0).unwrap();
        assert_eq!(wide.reach_cells(), None);
        assert!(g.with_reach(f32::NAN).is_err() && g.with_reach(0.0).is_err());
    }
}
