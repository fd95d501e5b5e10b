//! Building the photon map: a balanced kd-tree in one flat array of compact photons.
//!
//! It is Jensen's tree (every node a photon, split at the median along the largest
//! side of its photons' bounding box) stored in **in-order** rather than heap order:
//! the subtree of `n` photons starting at `lo` has its node at `lo + n / 2`, its left
//! subtree in `[lo, lo + n/2)` and its right subtree after the node. Why:
//! - a median split never leaves a hole, so no left-balancing and no permutation
//!   pass to heap order is needed: the build partitions the array in place, and its
//!   peak memory is the photon array itself (Jensen needs a second array);
//! - every subtree is contiguous, so once a subtree holds at most [`LEAF_SIZE`]
//!   photons a query scans it linearly (what kiddo's leaf buckets buy) and the build
//!   stops partitioning there. The tree's depth is `ceil(log2(n / LEAF_SIZE))`.
//!
//! Determinism: the order used to partition is total over the 16 bytes of a photon
//! and every leaf is sorted by it, so the array depends only on the *multiset* of
//! encoded photons: not on the input order, on the thread count, or on how
//! `select_nth_unstable_by` arranges equal elements.
//!
//! Parameters: [`LEAF_SIZE`] (query speed; measured in `benches/kdtree.rs`),
//! `PARALLEL_MIN` (subtrees smaller than this are built on one thread).

use super::boxes::{BoxSink, GridBox};
use super::photon::{CompactPhoton, Quantizer};
use super::stems;
use super::PhotonRecord;
use crate::rng::{hash2, mix64};
use glam::Vec3;
use rayon::prelude::*;

/// Subtrees of at most this many photons are leaves, scanned linearly by queries.
pub const LEAF_SIZE: usize = 24;

/// Subtrees smaller than this are built sequentially (below it, rayon's task
/// overhead outweighs the partitioning).
const PARALLEL_MIN: usize = 1 << 14;

/// A photon map: compact photons in a balanced kd-tree (see the module docs), with
/// the quantisation frame that decodes them.
#[derive(Clone, Debug)]
pub struct PhotonMap {
    pub(crate) photons: Vec<CompactPhoton>,
    pub(crate) quant: Quantizer,
    /// Smallest and largest grid coordinate per axis (see [`grid_bounds`]).
    pub(crate) bounds: [[f32; 3]; 2],
    /// The inner nodes' split planes, breadth-first ([`super::stems`]).
    pub(crate) stems: Vec<u32>,
    /// The larger subtrees' bounding boxes, breadth-first ([`super::boxes`]).
    pub(crate) boxes: Vec<GridBox>,
    skipped: usize,
}

impl PhotonMap {
    /// Builds the map from all valid records. The bounds are those of the valid
    /// positions. A record is skipped (and counted, see [`PhotonMap::skipped`]) when
    /// its position, power or direction is not finite or its direction is zero.
    /// Negative power channels are stored as 0. O(n log n), parallel with rayon and
    /// deterministic (see the module docs).
    ///
    /// # Panics
    /// If more than `u32::MAX` records are valid (indices are `u32`; the records
    /// alone would take 170 GB).
    pub fn build(records: &[PhotonRecord]) -> PhotonMap {
        Self::build_filtered(records, |_| true)
    }

    /// Like [`PhotonMap::build`] with only the records that `keep` accepts, for
    /// instance `|r| r.depth == 0` for a map of primary photons. Records that `keep`
    /// rejects are not counted as skipped.
    ///
    /// # Panics
    /// As [`PhotonMap::build`].
    pub fn build_filtered<F>(records: &[PhotonRecord], keep: F) -> PhotonMap
    where
        F: Fn(&PhotonRecord) -> bool + Sync,
    {
        // One pass for the bounds, the largest power and the invalid count; min, max
        // and integer sums are exact, so the reduction is deterministic in any order.
        let empty = || (Vec3::INFINITY, Vec3::NEG_INFINITY, 0.0f32, 0usize);
        let (min, max, max_power, skipped) = records
            .par_iter()
            .with_min_len(4096)
            .fold(empty, |(lo, hi, pw, bad), r| {
                if !is_valid(r) {
                    (lo, hi, pw, bad + 1)
                } else if keep(r) {
                    let p = r.power.max_element();
                    (lo.min(r.position), hi.max(r.position), pw.max(p), bad)
                } else {
                    (lo, hi, pw, bad)
                }
            })
            .reduce(empty, |a, b| {
                (a.0.min(b.0), a.1.max(b.1), a.2.max(b.2), a.3 + b.3)
            });
        let wanted = |r: &PhotonRecord| is_valid(r) && keep(r);
        let quant = Quantizer::new(min, max, max_power);
        // An indexed collect writes straight into one Vec of records.len(); the
        // marker + retain keeps the peak at one photon array.
        let mut photons: Vec<CompactPhoton> = records
            .par_iter()
            .with_min_len(4096)
            .map(|r| {
                if wanted(r) {
                    quant.encode(r)
                } else {
                    CompactPhoton::INVALID
                }
            })
            .collect();
        photons.retain(|p| *p != CompactPhoton::INVALID);
        assert!(
            photons.len() <= u32::MAX as usize,
            "a photon map holds at most u32::MAX photons"
        );
        let (bounds, boxes) = build_tree(&mut photons);
        PhotonMap {
            bounds,
            boxes,
            stems: stems::build(&photons),
            photons,
            quant,
            skipped,
        }
    }

    /// Builds the map in place over photons already encoded in `quant` (the
    /// tracer writes them so): no copy, the peak memory is `photons` itself.
    /// The tree depends only on the multiset of photons, as for
    /// [`PhotonMap::build`].
    ///
    /// # Panics
    /// If there are more than `u32::MAX` photons.
    pub fn from_compact(mut photons: Vec<CompactPhoton>, quant: Quantizer) -> PhotonMap {
        assert!(
            photons.len() <= u32::MAX as usize,
            "a photon map holds at most u32::MAX photons"
        );
        // Split axes of an earlier build would make equal photons differ.
        if photons.len() < PARALLEL_MIN {
            photons.iter_mut().for_each(|p| p.set_axis(0));
        } else {
            photons
                .par_iter_mut()
                .with_min_len(4096)
                .for_each(|p| p.set_axis(0));
        }
        let (bounds, boxes) = build_tree(&mut photons);
        PhotonMap {
            bounds,
            boxes,
            stems: stems::build(&photons),
            photons,
            quant,
            skipped: 0,
        }
    }

    /// The photons back, in tree order, with their frame.
    pub fn into_compact(self) -> (Vec<CompactPhoton>, Quantizer) {
        (self.photons, self.quant)
    }

    /// The compact photons, in tree order (their split-axis bits set).
    pub fn compact_photons(&self) -> &[CompactPhoton] {
        &self.photons
    }

    /// Number of photons.
    pub fn len(&self) -> usize {
        self.photons.len()
    }

    /// True when the map holds no photon.
    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }

    /// Records that [`PhotonMap::build`] skipped because they were not finite.
    pub fn skipped(&self) -> usize {
        self.skipped
    }

    /// The photon at `index` (tree order), decoded.
    ///
    /// # Panics
    /// If `index >= self.len()`.
    pub fn photon(&self, index: u32) -> PhotonRecord {
        self.quant.decode(&self.photons[index as usize])
    }

    /// The compact photon at `index` (tree order).
    ///
    /// # Panics
    /// If `index >= self.len()`.
    pub fn compact(&self, index: u32) -> &CompactPhoton {
        &self.photons[index as usize]
    }

    /// All photons, decoded, in tree order (the `n`-th item has index `n`).
    pub fn iter(&self) -> impl ExactSizeIterator<Item = PhotonRecord> + '_ {
        self.photons.iter().map(|p| self.quant.decode(p))
    }

    /// The frame the photons are quantised in (precision of the decoded values).
    pub fn quantizer(&self) -> &Quantizer {
        &self.quant
    }

    /// Bytes one stored photon takes (16).
    pub fn bytes_per_photon(&self) -> usize {
        std::mem::size_of::<CompactPhoton>()
    }

    /// Bytes the map holds: its allocated photon array, the split planes of
    /// its inner nodes (under 0.33 byte a photon), the boxes of its larger
    /// subtrees (under 0.1 byte a photon) and the struct itself.
    pub fn memory_bytes(&self) -> usize {
        self.photons.capacity() * std::mem::size_of::<CompactPhoton>()
            + self.stems.capacity() * std::mem::size_of::<u32>()
            + self.boxes.capacity() * std::mem::size_of::<GridBox>()
            + std::mem::size_of::<Self>()
    }

    /// A hash of the compact photons in tree order and of the quantisation frame:
    /// equal for equal maps, to check that builds are reproducible.
    pub fn checksum(&self) -> u64 {
        let frame = self.quant.bits().iter().fold(mix64(0), |h, &b| hash2(h, b));
        self.photons.iter().fold(frame, |h, p| {
            let (a, b) = p.bits();
            hash2(hash2(h, a), b)
        })
    }
}

/// Each axis's smallest and largest coordinate field of the photons'
/// packed positions, masked in place (a field orders as its coordinate).
type FieldBounds = ([u64; 3], [u64; 3]);

const NO_BOUNDS: FieldBounds = ([u64::MAX; 3], [0; 3]);

fn field_bounds(photons: &[CompactPhoton]) -> FieldBounds {
    // No shifts per photon: the fields are compared where they lie.
    let masks = [0, 1, 2].map(CompactPhoton::coord_mask);
    photons.iter().fold(NO_BOUNDS, |(mut lo, mut hi), p| {
        let pos = p.packed_position();
        for a in 0..3 {
            lo[a] = lo[a].min(pos & masks[a]);
            hi[a] = hi[a].max(pos & masks[a]);
        }
        (lo, hi)
    })
}

/// [`field_bounds`] in parallel chunks (min and max: the same in any order).
fn field_bounds_par(photons: &[CompactPhoton]) -> FieldBounds {
    if photons.len() < PARALLEL_MIN {
        return field_bounds(photons);
    }
    photons.par_chunks(PARALLEL_MIN).map(field_bounds).reduce(
        || NO_BOUNDS,
        |a, b| {
            (
                [0, 1, 2].map(|i| a.0[i].min(b.0[i])),
                [0, 1, 2].map(|i| a.1[i].max(b.1[i])),
            )
        },
    )
}

/// The photons' bounding box in grid units. Queries start from the gap to it:
/// the split planes alone bound only the axes split on, and a map of one plane
/// (a floor's caustic) is never split across it, so a query far off that plane
/// would otherwise visit every leaf.
fn grid_bounds((lo, hi): &FieldBounds) -> [[f32; 3]; 2] {
    // The same conversion as a photon's distance (`query::dist2`); an empty
    // map keeps the sentinel an empty fold gives.
    let coords = |fields: &[u64; 3]| {
        [0, 1, 2].map(|a| {
            let c = if fields[a] == u64::MAX {
                u32::MAX
            } else {
                CompactPhoton::field_value(fields[a], a)
            };
            c as i32 as f32
        })
    };
    [coords(lo), coords(hi)]
}

pub(super) fn is_valid(r: &PhotonRecord) -> bool {
    r.position.is_finite()
        && r.power.is_finite()
        && r.direction.is_finite()
        && r.direction != Vec3::ZERO
}

/// Turns `photons` into its kd-tree in place (see the module docs for the
/// layout) and returns their bounding box in grid units and the boxes of the
/// larger subtrees ([`super::boxes`]). The root's widest-axis pass is that
/// box's, done once and in parallel.
fn build_tree(photons: &mut [CompactPhoton]) -> ([[f32; 3]; 2], Vec<GridBox>) {
    let bounds = field_bounds_par(photons);
    let sink = BoxSink::new(photons.len());
    build_subtree(photons, Some(bounds), 0, &sink);
    (grid_bounds(&bounds), sink.finish())
}

/// [`build_tree`] of the subtree of breadth-first index `node`, whose field
/// bounds are known or not.
fn build_subtree(
    photons: &mut [CompactPhoton],
    bounds: Option<FieldBounds>,
    node: usize,
    sink: &BoxSink,
) {
    let n = photons.len();
    if n <= LEAF_SIZE {
        // By all 16 bytes, position first; a tie on it (rare) behind a branch.
        photons.sort_unstable_by(|a, b| {
            let (a, b) = (a.bits(), b.bits());
            if a.0 != b.0 {
                a.0.cmp(&b.0)
            } else {
                a.1.cmp(&b.1)
            }
        });
        return;
    }
    let bounds = bounds.unwrap_or_else(|| field_bounds(photons));
    sink.put(node, || grid_bounds(&bounds));
    let axis = widest_axis(&bounds);
    let mid = n / 2;
    // Only "less" matters to the selection (equal means bitwise equal).
    photons.select_nth_unstable_by(mid, |a, b| {
        if a.less_on(b, axis) {
            std::cmp::Ordering::Less
        } else {
            std::cmp::Ordering::Greater
        }
    });
    photons[mid].set_axis(axis);
    let (left, rest) = photons.split_at_mut(mid);
    let right = &mut rest[1..];
    if n >= PARALLEL_MIN {
        rayon::join(
            || build_subtree(left, None, 2 * node + 1, sink),
            || build_subtree(right, None, 2 * node + 2, sink),
        );
    } else {
        build_subtree(left, None, 2 * node + 1, sink);
        build_subtree(right, None, 2 * node + 2, sink);
    }
}

/// The axis along which the photons' bounding box is longest (ties: lowest axis).
fn widest_axis((lo, hi): &FieldBounds) -> usize {
    let ext = [0, 1, 2].map(|a| CompactPhoton::field_value(hi[a] - lo[a], a));
    if ext[0] >= ext[1] && ext[0] >= ext[2] {
        0
    } else if ext[1] >= ext[2] {
        1
    } else {
        2
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Checks the kd-tree invariant on every node: left coordinates <= the node's,
    /// right ones >= it, on the node's axis.
    fn check_subtree(p: &[CompactPhoton]) {
        let n = p.len();
        if n <= LEAF_SIZE {
            return;
        }
        let mid = n / 2;
        let (axis, split) = (p[mid].axis(), p[mid].coord(p[mid].axis()));
        assert!(p[..mid].iter().all(|q| q.coord(axis) <= split));
        assert!(p[mid + 1..].iter().all(|q| q.coord(axis) >= split));
        check_subtree(&p[..mid]);
        check_subtree(&p[mid + 1..]);
    }

    #[test]
    fn tree_invariant_holds_and_input_order_does_not_matter() {
        let mut rng = crate::rng::Rng::new(7);
        let mut records: Vec<PhotonRecord> = (0..5000)
            .map(|i| PhotonRecord {
                // A coarse lattice makes many equal coordinates (ties at splits).
                position: Vec3::new(
                    (rng.next_f32() * 8.0).floor(),
                    rng.next_f32(),
                    (i % 3) as f32,
                ),
                power: Vec3::splat(rng.next_f32()),
                direction: Vec3::Z,
                depth: (i % 4) as u8,
                caustic: false,
            })
            .collect();
        let map = PhotonMap::build(&records);
        check_subtree(&map.photons);
        records.reverse();
        assert_eq!(PhotonMap::build(&records).checksum(), map.checksum());
    }
}
