//! A photon map that can be queried while it grows, for density control (Suykens &
//! Willems 2000: a photon landing where the map is already dense enough is rejected
//! and its power handed to its neighbours, so the stored density follows a target).
//!
//! A uniform grid of cubic cells over the scene's bounds, hashed (only occupied cells
//! cost memory): an open-addressing table from a cell to the head of a linked list of
//! its photons, threaded through one `next` array. Insertion is O(1) amortised.
//! k-nearest queries visit cubic rings of cells around the query's cell and stop once
//! the ring radius exceeds the k-th distance (or `max_radius`); when a ring would have
//! more cells than the table has occupied cells, the rest is one scan of the table.
//!
//! Parameter: the cell size. A good one is about the radius that holds k photons at
//! the target surface density `D`: `sqrt(k / (pi D))`; then a query usually ends after
//! ring 1 (27 cells). Positions outside the bounds are stored in the nearest boundary
//! cell (queries stay exact); a photon with a non-finite position is stored but never
//! found.

use super::query::{heap_insert, sort_neighbors};
use super::{Neighbor, PhotonRecord};
use crate::error::{Error, Result};
use crate::rng::mix64;
use glam::Vec3;

/// Most cells along one axis (cell coordinates are packed in 21 bits).
const MAX_CELLS_PER_AXIS: i64 = 1 << 21;
const EMPTY_KEY: u64 = u64::MAX;
const NO_PHOTON: u32 = u32::MAX;
/// Rings end a search once `ring * cell * (1 - MARGIN)` exceeds the k-th distance:
/// the margin covers the f32 rounding of distances (relative 3e-7) and of cell
/// indices (f64), so results equal a brute-force search with the same f32 distances.
const MARGIN: f64 = 1e-5;

#[derive(Clone, Copy, Debug)]
struct Slot {
    key: u64,
    head: u32,
}

/// A hash grid of photons that accepts insertions between queries.
#[derive(Clone, Debug)]
pub struct GrowingMap {
    min: [f64; 3],
    cell: f64,
    inv_cell: f64,
    dims: [i64; 3],
    records: Vec<PhotonRecord>,
    /// Positions again, packed, for queries (12 bytes a photon instead of 40).
    positions: Vec<Vec3>,
    next: Vec<u32>,
    slots: Vec<Slot>,
    occupied: usize,
}

impl GrowingMap {
    /// An empty map over the box `[min, max]` with cubic cells of side `cell_size`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] if the bounds are not finite or inverted, if
    /// `cell_size` is not a finite positive number, or if the box is more than 2^21
    /// cells long on an axis.
    pub fn new(min: Vec3, max: Vec3, cell_size: f32) -> Result<Self> {
        if !(min.is_finite() && max.is_finite() && min.cmple(max).all()) {
            return Err(Error::param(
                "bounds",
                format!("must be finite with min <= max, got {min} .. {max}"),
            ));
        }
        if !(cell_size.is_finite() && cell_size > 0.0) {
            return Err(Error::param(
                "cell_size",
                format!("must be a finite number > 0, got {cell_size}"),
            ));
        }
        let cell = cell_size as f64;
        let mut dims = [1i64; 3];
        for (a, d) in dims.iter_mut().enumerate() {
            let n = ((max[a] as f64 - min[a] as f64) / cell).ceil();
            if n > MAX_CELLS_PER_AXIS as f64 {
                return Err(Error::param(
                    "cell_size",
                    format!("{cell_size} makes {n} cells along axis {a}, at most 2^21 allowed"),
                ));
            }
            *d = (n as i64).max(1);
        }
        Ok(GrowingMap {
            min: [min.x as f64, min.y as f64, min.z as f64],
            cell,
            inv_cell: 1.0 / cell,
            dims,
            records: Vec::new(),
            positions: Vec::new(),
            next: Vec::new(),
            slots: vec![
                Slot {
                    key: EMPTY_KEY,
                    head: NO_PHOTON
                };
                64
            ],
            occupied: 0,
        })
    }

    /// Number of photons.
    pub fn len(&self) -> usize {
        self.records.len()
    }

    /// True when the map holds no photon.
    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    /// The photon inserted as number `index`.
    ///
    /// # Panics
    /// If `index >= self.len()`.
    pub fn photon(&self, index: u32) -> &PhotonRecord {
        &self.records[index as usize]
    }

    /// Stores a photon and returns its index (the insertion count before it).
    ///
    /// # Panics
    /// If the map already holds `u32::MAX - 1` photons.
    pub fn insert(&mut self, r: PhotonRecord) -> u32 {
        let index = u32::try_from(self.records.len())
            .ok()
            .filter(|&i| i < NO_PHOTON)
            .expect("a growing map holds fewer than u32::MAX photons");
        if 2 * (self.occupied + 1) > self.slots.len() {
            self.grow_table();
        }
        let key = pack(self.cell_of(r.position));
        let s = self.find_slot(key);
        if self.slots[s].key == EMPTY_KEY {
            self.slots[s].key = key;
            self.occupied += 1;
        }
        self.next.push(self.slots[s].head);
        self.slots[s].head = index;
        self.records.push(r);
        self.positions.push(r.position);
        index
    }

    /// Adds `power` to the photon `index` (for instance its share of a rejected
    /// photon's power).
    ///
    /// # Panics
    /// If `index >= self.len()`.
    pub fn add_power(&mut self, index: u32, power: Vec3) {
        self.records[index as usize].power += power;
    }

    /// Splits `power` equally among `neighbors` (a rejected photon's power handed to
    /// the photons found around it). Does nothing if `neighbors` is empty.
    ///
    /// # Panics
    /// If a neighbor's index is out of range.
    pub fn spread_power(&mut self, neighbors: &[Neighbor], power: Vec3) {
        if neighbors.is_empty() {
            return;
        }
        let share = power / neighbors.len() as f32;
        for n in neighbors {
            self.add_power(n.index, share);
        }
    }

    /// The photons, in insertion order.
    pub fn into_records(self) -> Vec<PhotonRecord> {
        self.records
    }

    /// The photons, in insertion order.
    pub fn records(&self) -> &[PhotonRecord] {
        &self.records
    }

    /// The (at most) `k` photons nearest to `p` within `max_radius` (inclusive), in
    /// `out` (cleared first), sorted by increasing distance then index. Distances are
    /// `(position - p).length_squared()` in f32. Returns nothing for a non-finite `p`,
    /// `k == 0` or a negative or NaN radius.
    pub fn nearest_k(&self, p: Vec3, k: usize, max_radius: f32, out: &mut Vec<Neighbor>) {
        out.clear();
        if k == 0 || self.is_empty() || !p.is_finite() || max_radius.is_nan() || max_radius < 0.0 {
            return;
        }
        let r2 = max_radius * max_radius;
        let c = self.cell_of(p);
        let max_ring = (0..3)
            .map(|a| c[a].max(self.dims[a] - 1 - c[a]))
            .max()
            .unwrap_or(0);
        let visit = |head: u32, out: &mut Vec<Neighbor>| {
            let mut i = head;
            while i != NO_PHOTON {
                let d2 = (self.positions[i as usize] - p).length_squared();
                let enters = if out.len() == k {
                    d2 < out[0].dist2
                } else {
                    d2 <= r2
                };
                if enters {
                    heap_insert(
                        out,
                        k,
                        Neighbor {
                            index: i,
                            dist2: d2,
                        },
                    );
                }
                i = self.next[i as usize];
            }
        };
        for ring in 0..=max_ring {
            if ring > 0 && self.ring_cells(c, ring) > self.occupied as u64 {
                // Cheaper to scan every occupied cell not visited yet.
                for s in &self.slots {
                    if s.key != EMPTY_KEY && chebyshev(unpack(s.key), c) >= ring {
                        visit(s.head, out);
                    }
                }
                break;
            }
            self.for_ring(c, ring, |key| {
                let s = self.find_slot(key);
                if self.slots[s].key == key {
                    visit(self.slots[s].head, out);
                }
            });
            // Every photon within `covered` of p lies in a visited cell.
            let covered = ring as f64 * self.cell * (1.0 - MARGIN);
            if covered >= max_radius as f64
                || (out.len() == k && (out[0].dist2 as f64) <= covered * covered)
            {
                break;
            }
        }
        sort_neighbors(out);
    }

    /// Cell of a position, clamped into the grid (NaN goes to cell 0).
    fn cell_of(&self, p: Vec3) -> [i64; 3] {
        [0, 1, 2].map(|a| {
            let c = ((p[a] as f64 - self.min[a]) * self.inv_cell).floor();
            (c as i64).clamp(0, self.dims[a] - 1)
        })
    }

    /// Number of in-grid cells at Chebyshev distance exactly `ring` from `c`.
    fn ring_cells(&self, c: [i64; 3], ring: i64) -> u64 {
        let volume = |r: i64| -> u64 {
            (0..3)
                .map(|a| ((c[a] + r).min(self.dims[a] - 1) - (c[a] - r).max(0) + 1) as u64)
                .product()
        };
        volume(ring) - volume(ring - 1)
    }

    /// Calls `f` with the key of every in-grid cell at Chebyshev distance `ring` from `c`.
    fn for_ring(&self, c: [i64; 3], ring: i64, mut f: impl FnMut(u64)) {
        let lo = |a: usize| (c[a] - ring).max(0);
        let hi = |a: usize| (c[a] + ring).min(self.dims[a] - 1);
        for z in lo(2)..=hi(2) {
            let z_face = (z - c[2]).abs() == ring;
            for y in lo(1)..=hi(1) {
                if z_face || (y - c[1]).abs() == ring {
                    for x in lo(0)..=hi(0) {
                        f(pack([x, y, z]));
                    }
                } else {
                    // ring > 0 here: ring 0 is one cell on its own z face.
                    for x in [c[0] - ring, c[0] + ring] {
                        if x >= 0 && x < self.dims[0] {
                            f(pack([x, y, z]));
                        }
                    }
                }
            }
        }
    }

    /// The slot holding `key`, or the empty slot where it would go.
    fn find_slot(&self, key: u64) -> usize {
        let mask = self.slots.len() - 1;
        let mut s = mix64(key) as usize & mask;
        while self.slots[s].key != key && self.slots[s].key != EMPTY_KEY {
            s = (s + 1) & mask;
        }
        s
    }

    fn grow_table(&mut self) {
        let len = self.slots.len() * 2;
        let old = std::mem::replace(
            &mut self.slots,
            vec![
                Slot {
                    key: EMPTY_KEY,
                    head: NO_PHOTON
                };
                len
            ],
        );
        for s in old.into_iter().filter(|s| s.key != EMPTY_KEY) {
            let t = self.find_slot(s.key);
            self.slots[t] = s;
        }
    }
}

fn pack(c: [i64; 3]) -> u64 {
    c[0] as u64 | ((c[1] as u64) << 21) | ((c[2] as u64) << 42)
}

fn unpack(key: u64) -> [i64; 3] {
    let m = (1u64 << 21) - 1;
    [
        (key & m) as i64,
        ((key >> 21) & m) as i64,
        ((key >> 42) & m) as i64,
    ]
}

fn chebyshev(a: [i64; 3], b: [i64; 3]) -> i64 {
    (0..3).map(|i| (a[i] - b[i]).abs()).max().unwrap_or(0)
}
