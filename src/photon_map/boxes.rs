//! Tight bounding boxes of the kd-tree's larger subtrees, in the stems'
//! breadth-first order, so that a query can prune a subtree on every axis.
//!
//! Why: a query bounds a subtree by the per-axis gaps of the split planes
//! above it, and those bound only the axes that were split on. The primary
//! map of a sharp light is a spot on the floor, plus a few photons up the
//! walls that make the root's box the whole room: none of the floor's
//! subtrees is split on the vertical, so a k-nearest query from the ceiling,
//! whose 50 nearest photons are on the walls, read every floor photon
//! (0.3 ms a query against 10 µs; 60 % of the paper's sweep's density
//! statistics). A subtree's own box tells that the floor is too far.
//!
//! Cost: the build already computes each inner node's box to pick its split
//! axis ([`super::kdtree`]), so keeping the boxes of subtrees of more than
//! [`BOX_MIN`] photons costs no pass over the photons; 24 bytes each, under
//! 0.1 byte a photon.
//!
//! Exactness: a box's corners are photons' grid coordinates converted as a
//! photon's distance converts them, so a box's gap never exceeds the distance
//! of a photon inside, and the queries return what they returned without it.

use std::sync::atomic::{AtomicU32, Ordering};

/// Subtrees of more than this many photons keep their box.
pub(crate) const BOX_MIN: usize = 512;

/// A box in grid units: lowest and highest coordinate per axis.
pub(crate) type GridBox = [[f32; 3]; 2];

/// Number of breadth-first slots that hold boxes for an `n`-photon tree:
/// `2^D - 1` for the `D` levels whose leftmost (largest) subtree has more
/// than [`BOX_MIN`] photons. A right sibling has at most one photon fewer
/// per level than its left, so every slot is an inner node.
pub(crate) fn slots(n: usize) -> usize {
    super::stems::slots_above(n, BOX_MIN)
}

/// Where the build writes the boxes it computes, from any thread: each slot
/// is written once, by the node that owns it, so the result does not depend
/// on the thread count.
pub(crate) struct BoxSink {
    bits: Vec<[AtomicU32; 6]>,
}

impl BoxSink {
    pub(crate) fn new(n: usize) -> Self {
        BoxSink {
            bits: (0..slots(n))
                .map(|_| std::array::from_fn(|_| AtomicU32::new(0)))
                .collect(),
        }
    }

    /// Records the box of inner node `node`, computed by `b` only when the
    /// node has a slot.
    pub(crate) fn put(&self, node: usize, b: impl FnOnce() -> GridBox) {
        if let Some(slot) = self.bits.get(node) {
            for (i, v) in b().iter().flatten().enumerate() {
                slot[i].store(v.to_bits(), Ordering::Relaxed);
            }
        }
    }

    /// The boxes, by breadth-first index.
    pub(crate) fn finish(self) -> Vec<GridBox> {
        self.bits
            .into_iter()
            .map(|slot| {
                let v = slot.map(|a| f32::from_bits(a.into_inner()));
                [[v[0], v[1], v[2]], [v[3], v[4], v[5]]]
            })
            .collect()
    }
}

/// Per-axis gaps from `q` to `b`: the subtraction [`super::query`]'s
/// distance does, so no gap exceeds a photon's own per-axis distance.
#[inline(always)]
pub(crate) fn gaps(b: &GridBox, q: &[f32; 3]) -> [f32; 3] {
    let [lo, hi] = b;
    [0, 1, 2].map(|a| {
        if q[a] < lo[a] {
            lo[a] - q[a]
        } else if q[a] > hi[a] {
            q[a] - hi[a]
        } else {
            0.0
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photon_map::kdtree::LEAF_SIZE;

    /// Every slot's subtree is an inner node: larger than a leaf on the
    /// rightmost path too, the smallest at each depth.
    #[test]
    fn every_slot_is_an_inner_node() {
        for n in [0, 1, BOX_MIN, BOX_MIN + 1, 1025, 4097, 100_003, 1 << 22] {
            let levels = slots(n).count_ones() as usize;
            let mut right = n;
            for _ in 0..levels {
                assert!(right > LEAF_SIZE, "n = {n}");
                right = right - right / 2 - 1;
            }
        }
    }

    #[test]
    fn a_box_round_trips_through_the_sink() {
        let sink = BoxSink::new(4 * BOX_MIN);
        let b = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.5]];
        sink.put(2, || b);
        sink.put(1 << 20, || b);
        let boxes = sink.finish();
        assert_eq!(boxes.len(), 3);
        assert_eq!(boxes[2], b);
        assert_eq!(gaps(&b, &[0.0, 5.0, 7.0]), [1.0, 0.0, 0.5]);
    }
}
