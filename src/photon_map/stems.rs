//! The split planes of the kd-tree's inner nodes, apart from the photons, in
//! breadth-first (Eytzinger) order: node `i`'s children are `2i + 1` (left)
//! and `2i + 2` (right).
//!
//! Why: in the in-order layout (see [`super::kdtree`]) an inner node is a
//! photon in the middle of its subtree, so descending the tree reads one
//! 16-byte photon per level, each in a different cache line, and below the
//! first dozen levels of a large map each read misses the cache: on a 1M map
//! these misses were about 40 % of a k = 50 query. A stem is 4 bytes (the
//! split coordinate and axis), and the stems of a 1M map (256 KiB) stay in
//! the L2 cache; a query reads the node photon itself only when it could
//! enter the result, which the split plane's gap tells without reading it.
//! kiddo's immutable tree keeps its stems apart in the same way.
//!
//! Size: at most `2n / (LEAF_SIZE + 1)` stems, under 0.33 byte per photon.

use super::kdtree::LEAF_SIZE;
use super::photon::CompactPhoton;
use rayon::prelude::*;

/// Bit position of the split axis in a stem; the coordinate is below it.
const AXIS_SHIFT: u32 = 30;
const COORD_MASK: u32 = (1 << AXIS_SHIFT) - 1;

/// A stem of no inner node (a leaf's slot in the breadth-first order).
const NO_NODE: u32 = u32::MAX;

/// One stem: the node's split axis and its coordinate on that axis.
#[inline(always)]
pub(crate) fn split(stem: u32) -> (usize, u32) {
    ((stem >> AXIS_SHIFT) as usize, stem & COORD_MASK)
}

/// Number of breadth-first slots the inner nodes of an `n`-photon tree need:
/// `2^D - 1` for `D` inner levels. A left subtree is never smaller than its
/// sibling (`n / 2` against `n - n / 2 - 1`), so the leftmost path is the
/// deepest.
fn slots(n: usize) -> usize {
    slots_above(n, LEAF_SIZE)
}

/// `2^D - 1` breadth-first slots for the `D` levels of an `n`-photon tree
/// whose leftmost (largest) subtree has more than `min` photons.
pub(crate) fn slots_above(n: usize, min: usize) -> usize {
    let mut levels = 0;
    let mut m = n;
    while m > min {
        levels += 1;
        m /= 2;
    }
    (1usize << levels) - 1
}

/// The range `(start, len)` of the subtree at breadth-first index `i`, found
/// by descending from the root along the bits of `i + 1`; `None` when the
/// path reaches a leaf first (no inner node has that index).
fn subtree(n: usize, i: usize) -> Option<(usize, usize)> {
    let path = i + 1;
    let (mut start, mut len) = (0usize, n);
    for bit in (0..path.ilog2()).rev() {
        if len <= LEAF_SIZE {
            return None;
        }
        let mid = len / 2;
        if path >> bit & 1 == 0 {
            len = mid;
        } else {
            start += mid + 1;
            len -= mid + 1;
        }
    }
    (len > LEAF_SIZE).then_some((start, len))
}

/// The stems of the tree in `photons` (built by `kdtree::build_subtree`).
/// Each is found independently of the others, so large maps fill them in
/// parallel; the result does not depend on the thread count.
pub(crate) fn build(photons: &[CompactPhoton]) -> Vec<u32> {
    let n = photons.len();
    let stem = |i: usize| match subtree(n, i) {
        Some((start, len)) => {
            let node = &photons[start + len / 2];
            let axis = node.axis();
            ((axis as u32) << AXIS_SHIFT) | node.coord(axis)
        }
        None => NO_NODE,
    };
    let count = slots(n);
    if count < 4096 {
        (0..count).map(stem).collect()
    } else {
        (0..count)
            .into_par_iter()
            .with_min_len(1024)
            .map(stem)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every inner node found by walking the in-order tree, by breadth-first index.
    fn walk(start: usize, len: usize, i: usize, out: &mut Vec<(usize, usize, usize)>) {
        if len <= LEAF_SIZE {
            return;
        }
        out.push((i, start, len));
        let mid = len / 2;
        walk(start, mid, 2 * i + 1, out);
        walk(start + mid + 1, len - mid - 1, 2 * i + 2, out);
    }

    #[test]
    fn every_inner_node_has_its_slot_and_no_leaf_has_one() {
        for n in [0, 1, 24, 25, 49, 50, 51, 100, 1000, 4097, 100_003] {
            let mut nodes = Vec::new();
            walk(0, n, 0, &mut nodes);
            let count = slots(n);
            assert!(nodes.iter().all(|&(i, ..)| i < count), "n = {n}");
            let inner: std::collections::HashMap<usize, (usize, usize)> =
                nodes.iter().map(|&(i, s, l)| (i, (s, l))).collect();
            for i in 0..count {
                assert_eq!(subtree(n, i), inner.get(&i).copied(), "n = {n}, i = {i}");
            }
            // The slots are not oversized: the last level holds a node.
            if count > 0 {
                assert!(nodes.iter().any(|&(i, ..)| i >= count / 2), "n = {n}");
                assert!(count <= 2 * n / (LEAF_SIZE + 1), "n = {n}");
            }
        }
    }

    #[test]
    fn a_stem_keeps_axis_and_coordinate() {
        let stem = (2 << AXIS_SHIFT) | ((1 << 21) - 1);
        assert_eq!(split(stem), (2, (1 << 21) - 1));
    }
}
