//! The importance grid's lookup table: the sums frozen into 8-byte slots,
//! half full, one probe per lookup (the layout is in the module docs of
//! [`super`]).

use super::grid::{CellGrid, ImportanceSums, ADJOINT_COARSENING, FIXED_ONE};
use crate::rng::mix64;
use glam::Vec3;
use std::collections::{BTreeSet, HashMap};

/// One slot: a tag of the cell's key (0 = empty), the read importance
/// (bf16; in a reach cube's slot, only its sign bit: photons there are
/// stored) and the adjoint (bf16).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Slot {
    tag: u32,
    read: u16,
    adjoint: u16,
}

/// The sign bit of a reach cube's read field: photons there are stored.
const STORED: u16 = 0x8000;

/// f32 to bfloat16, rounded to nearest even (positive finite values stay
/// positive).
fn to_bf16(v: f32) -> u16 {
    let b = v.max(0.0).to_bits();
    let rounded = b.saturating_add(0x7FFF + ((b >> 16) & 1));
    ((rounded >> 16) as u16).max(u16::from(b > 0))
}

fn from_bf16(v: u16) -> f32 {
    f32::from_bits(u32::from(v & !STORED) << 16)
}

/// Importance per unit area in the cells of a hashed grid, one probe per
/// lookup (module docs of [`super`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ImportanceGrid {
    slots: Vec<Slot>,
    grid: CellGrid,
    cells: usize,
    adjoint_ref: f32,
    stores_everywhere: bool,
}

impl ImportanceGrid {
    pub(super) fn from_sums(sums: &ImportanceSums) -> Self {
        // read = first + gather, adjoint = all three.
        let mut values: HashMap<u64, (f32, f32, bool)> = HashMap::new();
        for (k, s) in &sums.cells {
            let read = sums.density(s, 0) + sums.density(s, 1);
            let adjoint = read + sums.density(s, 2);
            values.insert(*k, (read as f32, adjoint as f32, false));
        }
        // The store rule: a kernel at a read point reads photons up to the
        // render's radius away, on any surface turned less than 90 degrees
        // from its own, so the reach cubes within that radius of a read
        // cell are flagged, on every side.
        let reach = sums.grid.reach_cells();
        if let Some(d) = reach {
            let seeds: BTreeSet<u64> = sums
                .cells
                .iter()
                .filter(|(_, s)| s[0] > 0 || s[1] > 0)
                .map(|(k, _)| CellGrid::reach_of(*k))
                .collect();
            for seed in seeds {
                for k in CellGrid::around(seed, d) {
                    values.insert(k, (0.0, 0.0, true));
                }
            }
        }
        // The coarse cells' adjoint: every reader's deposits over their
        // (4 h)^2.
        let mut coarse: HashMap<u64, u128> = HashMap::new();
        for (k, s) in &sums.cells {
            let sum: u128 = s.iter().map(|&v| u128::from(v)).sum();
            *coarse.entry(CellGrid::coarse_of(*k)).or_default() += sum;
        }
        let side = f64::from(sums.grid.cell_size()) * ADJOINT_COARSENING as f64;
        let area = sums.samples.max(1) as f64 * side * side;
        for (k, sum) in coarse {
            let adjoint = (sum as f64 / FIXED_ONE / area) as f32;
            values.insert(k, (0.0, adjoint, false));
        }
        let mut keys: Vec<u64> = values.keys().copied().collect();
        keys.sort_unstable();
        let mut grid = ImportanceGrid {
            slots: vec![Slot::default(); (2 * keys.len()).max(1)],
            grid: sums.grid,
            cells: keys.len(),
            adjoint_ref: 0.0,
            stores_everywhere: reach.is_none(),
        };
        for k in keys {
            let (read, adjoint, stored) = values[&k];
            let read = if stored { STORED } else { to_bf16(read) };
            grid.insert(k, read, to_bf16(adjoint));
        }
        // The mean adjoint of the read cells, at their coarse cells.
        let (mut adjoint_sum, mut read_cells) = (0.0f64, 0u64);
        for (k, s) in &sums.cells {
            if s[0] > 0 || s[1] > 0 {
                adjoint_sum +=
                    f64::from(from_bf16(grid.probe_key(CellGrid::coarse_of(*k)).adjoint));
                read_cells += 1;
            }
        }
        grid.adjoint_ref = (adjoint_sum / read_cells.max(1) as f64) as f32;
        grid
    }

    fn home(&self, hash: u64) -> usize {
        ((hash as u32 as u64 * self.slots.len() as u64) >> 32) as usize
    }

    fn insert(&mut self, key: u64, read: u16, adjoint: u16) {
        let hash = mix64(key);
        let tag = (hash >> 32) as u32 | 1;
        let mut i = self.home(hash);
        while self.slots[i].tag != 0 {
            i = if i + 1 == self.slots.len() { 0 } else { i + 1 };
        }
        self.slots[i] = Slot { tag, read, adjoint };
    }

    fn probe(&self, x: Vec3, n: Vec3) -> Slot {
        self.probe_key(self.grid.key(x, n))
    }

    fn probe_key(&self, key: u64) -> Slot {
        let hash = mix64(key);
        let tag = (hash >> 32) as u32 | 1;
        let mut i = self.home(hash);
        loop {
            match self.slots.get(i) {
                Some(s) if s.tag == tag => return *s,
                Some(s) if s.tag != 0 => {}
                _ => return Slot::default(),
            }
            i = if i + 1 == self.slots.len() { 0 } else { i + 1 };
        }
    }

    /// Importance per unit area and camera sample where the render reads
    /// photons (first and gather hits) at `x`, seen from the side of `n`.
    pub fn read(&self, x: Vec3, n: Vec3) -> f32 {
        from_bf16(self.probe(x, n).read)
    }

    /// True when a photon at `x` is stored: a kernel of the render's radius
    /// ([`CellGrid::reach`]) at a read point may return it.
    pub fn within_reach(&self, x: Vec3) -> bool {
        self.stores_everywhere || self.probe_key(self.grid.reach_key(x)).read & STORED != 0
    }

    /// The adjoint estimate at `x` (side of `n`): the importance of what
    /// is read there plus what camera paths bring there from later bounces.
    pub fn adjoint(&self, x: Vec3, n: Vec3) -> f32 {
        from_bf16(self.probe_key(self.grid.coarse_key(x, n)).adjoint)
    }

    /// The mean adjoint over the read cells: the reference alpha_I divides by.
    pub fn adjoint_reference(&self) -> f32 {
        self.adjoint_ref
    }

    /// Cells in the table (read cells, cells with an adjoint, and the
    /// flagged reach cubes).
    pub fn len(&self) -> usize {
        self.cells
    }

    /// True when no cell holds anything.
    pub fn is_empty(&self) -> bool {
        self.cells == 0
    }

    /// The cells' geometry.
    pub fn grid(&self) -> CellGrid {
        self.grid
    }

    /// Bytes of the table per cell: 8-byte slots, half full, so 16.
    pub fn bytes_per_cell(&self) -> usize {
        (self.slots.len() * std::mem::size_of::<Slot>()).div_ceil(self.cells.max(1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::importance::grid::{to_fixed, Accumulator};

    #[test]
    fn bf16_keeps_two_significant_digits_and_zero() {
        for v in [1.0f32, 3.7e-5, 12345.0, 1e-30] {
            let back = from_bf16(to_bf16(v));
            assert!((back - v).abs() <= v / 256.0, "{v} -> {back}");
        }
        assert_eq!(from_bf16(to_bf16(0.0)), 0.0);
        assert_eq!(from_bf16(to_bf16(-1.0)), 0.0);
    }

    #[test]
    fn a_frozen_cell_reads_back_its_density() {
        let g = CellGrid::for_bounds(Vec3::ZERO, Vec3::ONE, 0.25).unwrap();
        let mut acc = Accumulator::default();
        let x = Vec3::new(0.1, 0.5, 0.1);
        acc.add(g.key(x, Vec3::Y), 0, to_fixed(2.0));
        acc.add(g.key(x, Vec3::Y), 2, to_fixed(1.0));
        let grid = acc.into_sums(g, 4).freeze();
        let h = g.cell_size();
        let want = 2.0 / (4.0 * h * h);
        assert!((grid.read(x, Vec3::Y) / want - 1.0).abs() < 1.0 / 128.0);
        // The adjoint is the coarse cell's: 16 times the area.
        let coarse = 1.5 * want / 16.0;
        assert!((grid.adjoint(x, Vec3::Y) / coarse - 1.0).abs() < 1.0 / 128.0);
        assert_eq!(
            CellGrid::coarse_of(g.key(x, Vec3::Y)),
            g.coarse_key(x, Vec3::Y)
        );
        let below = Vec3::new(-0.01, 0.5, 0.1);
        assert_eq!(
            CellGrid::coarse_of(g.key(below, Vec3::Y)),
            g.coarse_key(below, Vec3::Y)
        );
        assert_eq!(grid.read(x, -Vec3::Y), 0.0);
        // Photons are stored within the reach (a tenth of the diagonal:
        // one reach cube of 4 h = 1 a side here), on every side, and not
        // beyond it.
        let d = g.reach_cells().unwrap() as f32;
        let cube = 4.0 * h;
        assert!(grid.within_reach(x + Vec3::X * g.reach()));
        assert!(grid.within_reach(x - Vec3::Y * g.reach()));
        assert!(!grid.within_reach(x + Vec3::Z * (d + 1.0) * cube));
        assert!(grid.bytes_per_cell() <= 16);
    }
}
