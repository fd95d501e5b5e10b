//! Queries of a [`PhotonMap`]: k nearest photons and photons within a radius.
//!
//! Distances are computed in grid units (the query point is converted once, photons
//! are compared on their quantised coordinates, no decoding), in f32, and reported
//! in world units. Pruning is exact: a subtree's lower bound is the sum of squared
//! per-axis gaps to its region (Arya & Mount's incremental distance), computed with
//! the same operations as a photon's distance, so float rounding cannot make the
//! bound exceed the distance of a photon inside.
//!
//! Query points more than 2^40 grid steps (2^19 map extents) from the map are moved
//! to that distance first, which keeps squared distances finite in f32.
//!
//! Bad arguments return no photon: a non-finite query point, `k == 0`, a negative or
//! NaN radius. A radius of 0 returns the photons exactly at the query point (at its
//! quantised position) and an infinite radius is unbounded.

use super::boxes::{self, GridBox};
use super::kdtree::{PhotonMap, LEAF_SIZE};
use super::photon::CompactPhoton;
use super::stems;
use super::Neighbor;
use glam::Vec3;

impl PhotonMap {
    /// The (at most) `k` photons nearest to `p` within `max_radius` (inclusive),
    /// written to `out` (cleared first) **sorted by increasing distance** (ties by
    /// index). Among photons at exactly the k-th distance, which are kept is
    /// deterministic but not specified.
    pub fn nearest_k(&self, p: Vec3, k: usize, max_radius: f32, out: &mut Vec<Neighbor>) {
        self.nearest_k_where(p, k, max_radius, out, |_| true);
    }

    /// Like [`PhotonMap::nearest_k`], counting only photons that arrived on the side
    /// of the surface that `normal` points to: those whose direction of travel `d`
    /// has `dot(d, normal) <= 0`. A zero `normal` accepts every photon.
    pub fn nearest_k_facing(
        &self,
        p: Vec3,
        normal: Vec3,
        k: usize,
        max_radius: f32,
        out: &mut Vec<Neighbor>,
    ) {
        self.nearest_k_where(p, k, max_radius, out, |c| {
            // The octahedral vector has the sign of the direction's dot products.
            c.direction_unnormalised().dot(normal) <= 0.0
        });
    }

    /// The `k` nearest photons that `accept` keeps (see [`PhotonMap::nearest_k`]).
    /// `accept` is called only for photons close enough to enter the result.
    pub fn nearest_k_where<F>(
        &self,
        p: Vec3,
        k: usize,
        max_radius: f32,
        out: &mut Vec<Neighbor>,
        accept: F,
    ) where
        F: Fn(&CompactPhoton) -> bool,
    {
        self.search_k(p, k, max_radius, out, accept);
        sort_neighbors(out);
        for n in out.iter_mut() {
            n.dist2 = self.quant.world_dist2(n.dist2);
        }
    }

    /// How many of the `k` nearest photons that `accept` keeps were found,
    /// and the squared world distance of the farthest (`None` when none
    /// was): what a density estimate reads of [`PhotonMap::nearest_k_where`],
    /// with the same values, without sorting the neighbours. `scratch` is
    /// reused between calls.
    pub fn kth_nearest_where<F>(
        &self,
        p: Vec3,
        k: usize,
        scratch: &mut Vec<Neighbor>,
        accept: F,
    ) -> Option<(usize, f32)>
    where
        F: Fn(&CompactPhoton) -> bool,
    {
        self.search_k(p, k, f32::INFINITY, scratch, accept);
        // The heap's root is its farthest entry.
        let far = scratch.first()?;
        Some((scratch.len(), self.quant.world_dist2(far.dist2)))
    }

    /// The k-nearest search: `out` is left a max-heap on grid distance.
    fn search_k<F>(&self, p: Vec3, k: usize, max_radius: f32, out: &mut Vec<Neighbor>, accept: F)
    where
        F: Fn(&CompactPhoton) -> bool,
    {
        out.clear();
        if k == 0 || self.is_empty() || !p.is_finite() || max_radius.is_nan() || max_radius < 0.0 {
            return;
        }
        let r = self.quant.grid_length(max_radius);
        let mut search = Knn {
            q: self.quant.grid_point(p),
            stems: &self.stems,
            boxes: &self.boxes,
            k,
            r2: (r * r).min(f32::MAX as f64) as f32,
            heap: out,
            accept,
        };
        if max_radius == f32::INFINITY {
            search.r2 = f32::INFINITY;
        }
        let off = self.root_gap(&search.q);
        search.visit(&self.photons, 0, off, 0);
    }

    /// Every photon within `radius` of `p` (inclusive), written to `out` (cleared
    /// first) in an unspecified but deterministic order (sort by `dist2` if needed).
    pub fn within_radius(&self, p: Vec3, radius: f32, out: &mut Vec<Neighbor>) {
        out.clear();
        if self.is_empty() || !p.is_finite() || radius.is_nan() || radius < 0.0 {
            return;
        }
        let r = self.quant.grid_length(radius);
        let mut search = Within {
            q: self.quant.grid_point(p),
            stems: &self.stems,
            boxes: &self.boxes,
            r2: if radius == f32::INFINITY {
                f32::INFINITY
            } else {
                (r * r).min(f32::MAX as f64) as f32
            },
            out,
        };
        let off = self.root_gap(&search.q);
        search.visit(&self.photons, 0, off, 0);
        for n in out.iter_mut() {
            n.dist2 = self.quant.world_dist2(n.dist2);
        }
    }
}

impl PhotonMap {
    /// Per-axis gaps from `q` (grid units) to the photons' bounding box: the
    /// root's region ([`boxes::gaps`], the same subtraction as [`dist2`]'s).
    fn root_gap(&self, q: &[f32; 3]) -> [f32; 3] {
        boxes::gaps(&self.bounds, q)
    }
}

/// Squared distance in grid units.
#[inline(always)]
fn dist2(q: &[f32; 3], p: &CompactPhoton) -> f32 {
    let g = p.grid();
    let dx = q[0] - g[0] as i32 as f32;
    let dy = q[1] - g[1] as i32 as f32;
    let dz = q[2] - g[2] as i32 as f32;
    dx * dx + dy * dy + dz * dz
}

/// Lower bound of the distance to a region, given its per-axis gaps; the same
/// operations as [`dist2`] so that it never exceeds the distance of a photon inside.
#[inline(always)]
fn gap2(off: &[f32; 3]) -> f32 {
    off[0] * off[0] + off[1] * off[1] + off[2] * off[2]
}

/// The larger of the split planes' gaps `off` and the gaps to the subtree's
/// own box, per axis: both are lower bounds of every photon's distance on
/// that axis, so their maximum is too.
#[inline(always)]
fn tighten(off: [f32; 3], b: &GridBox, q: &[f32; 3]) -> [f32; 3] {
    let g = boxes::gaps(b, q);
    [0, 1, 2].map(|a| off[a].max(g[a]))
}

/// A subtree: its photons, where they start in the map, its stem index.
type Subtree<'a> = (&'a [CompactPhoton], usize, usize);

/// The two children of the inner node `node` (whose subtree `photons` starts
/// at `base`), the near one first: the left one when `left_is_near`.
#[inline(always)]
fn children(
    photons: &[CompactPhoton],
    base: usize,
    node: usize,
    left_is_near: bool,
) -> [Subtree<'_>; 2] {
    let mid = photons.len() / 2;
    let left = (&photons[..mid], base, 2 * node + 1);
    let right = (&photons[mid + 1..], base + mid + 1, 2 * node + 2);
    if left_is_near {
        [left, right]
    } else {
        [right, left]
    }
}

/// Inserts `n` into `heap`, a max-heap on `dist2` of at most `k` entries: pushed when
/// the heap is not full, else it replaces the farthest (the caller checks that `n` is
/// nearer than it).
fn heap_insert(heap: &mut Vec<Neighbor>, k: usize, n: Neighbor) {
    if heap.len() < k {
        heap.push(n);
        let mut i = heap.len() - 1;
        while i > 0 {
            let parent = (i - 1) / 2;
            if heap[parent].dist2 >= n.dist2 {
                break;
            }
            heap[i] = heap[parent];
            i = parent;
        }
        heap[i] = n;
    } else {
        let len = heap.len();
        let mut i = 0;
        loop {
            let l = 2 * i + 1;
            if l >= len {
                break;
            }
            let r = l + 1;
            let c = if r < len && heap[r].dist2 > heap[l].dist2 {
                r
            } else {
                l
            };
            if heap[c].dist2 <= n.dist2 {
                break;
            }
            heap[i] = heap[c];
            i = c;
        }
        heap[i] = n;
    }
}

/// Sorts a finished k-nearest result by distance, then index.
fn sort_neighbors(out: &mut [Neighbor]) {
    // One integer key in the order of `(dist2.total_cmp, index)`: a sort of
    // plain u64s, about twice as fast as comparing floats and then indices.
    out.sort_unstable_by_key(|n| {
        let bits = n.dist2.to_bits();
        // `total_cmp`'s order as unsigned integers: negative values flipped.
        let ordered = bits ^ (((bits as i32 >> 31) as u32) | 1 << 31);
        u64::from(ordered) << 32 | u64::from(n.index)
    });
}

/// k-nearest search state; `heap` is a max-heap on `dist2` (grid units) while searching.
struct Knn<'a, F> {
    q: [f32; 3],
    stems: &'a [u32],
    boxes: &'a [GridBox],
    k: usize,
    r2: f32,
    heap: &'a mut Vec<Neighbor>,
    accept: F,
}

impl<F: Fn(&CompactPhoton) -> bool> Knn<'_, F> {
    /// Whether a region at squared gap `g2` may hold a photon that enters the result.
    #[inline(always)]
    fn may_enter(&self, g2: f32) -> bool {
        if self.heap.len() == self.k {
            g2 < self.heap[0].dist2
        } else {
            g2 <= self.r2
        }
    }

    #[inline(always)]
    fn consider(&mut self, index: usize, p: &CompactPhoton) {
        let d2 = dist2(&self.q, p);
        if self.may_enter(d2) && (self.accept)(p) {
            self.insert(Neighbor {
                index: index as u32,
                dist2: d2,
            });
        }
    }

    #[inline]
    fn insert(&mut self, n: Neighbor) {
        heap_insert(self.heap, self.k, n);
    }

    /// Searches the subtree `photons` (which starts at `base` in the map, and
    /// whose inner node, if any, is stem `node`); `off` are the per-axis gaps
    /// from the query point to the subtree's region.
    fn visit(&mut self, photons: &[CompactPhoton], base: usize, mut off: [f32; 3], node: usize) {
        let n = photons.len();
        if n <= LEAF_SIZE {
            // Distances first, in a loop the compiler can vectorise; then the heap.
            let mut d2 = [0.0f32; LEAF_SIZE];
            for (d, p) in d2.iter_mut().zip(photons) {
                *d = dist2(&self.q, p);
            }
            for (i, (&d, p)) in d2.iter().zip(photons).enumerate() {
                if self.may_enter(d) && (self.accept)(p) {
                    self.insert(Neighbor {
                        index: (base + i) as u32,
                        dist2: d,
                    });
                }
            }
            return;
        }
        if let Some(b) = self.boxes.get(node) {
            off = tighten(off, b, &self.q);
            if !self.may_enter(gap2(&off)) {
                return;
            }
        }
        let mid = n / 2;
        let (axis, split) = stems::split(self.stems[node]);
        let d = self.q[axis] - split as f32;
        let [near, far] = children(photons, base, node, d < 0.0);
        self.visit(near.0, near.1, off, near.2);
        // The node photon is at least |d| away (its distance adds squares to
        // d * d, rounding up or not at all): read it only if that could enter.
        if self.may_enter(d * d) {
            self.consider(base + mid, &photons[mid]);
        }
        off[axis] = d.abs();
        if self.may_enter(gap2(&off)) {
            self.visit(far.0, far.1, off, far.2);
        }
    }
}

/// Fixed-radius search state (grid units while searching).
struct Within<'a> {
    q: [f32; 3],
    stems: &'a [u32],
    boxes: &'a [GridBox],
    r2: f32,
    out: &'a mut Vec<Neighbor>,
}

impl Within<'_> {
    #[inline(always)]
    fn consider(&mut self, index: usize, p: &CompactPhoton) {
        let d2 = dist2(&self.q, p);
        if d2 <= self.r2 {
            self.out.push(Neighbor {
                index: index as u32,
                dist2: d2,
            });
        }
    }

    fn visit(&mut self, photons: &[CompactPhoton], base: usize, mut off: [f32; 3], node: usize) {
        let n = photons.len();
        if n <= LEAF_SIZE {
            for (i, p) in photons.iter().enumerate() {
                self.consider(base + i, p);
            }
            return;
        }
        if let Some(b) = self.boxes.get(node) {
            off = tighten(off, b, &self.q);
            if gap2(&off) > self.r2 {
                return;
            }
        }
        let mid = n / 2;
        let (axis, split) = stems::split(self.stems[node]);
        let d = self.q[axis] - split as f32;
        let [near, far] = children(photons, base, node, d < 0.0);
        self.visit(near.0, near.1, off, near.2);
        // As for k nearest: the node photon is at least |d| away.
        if d * d <= self.r2 {
            self.consider(base + mid, &photons[mid]);
        }
        off[axis] = d.abs();
        if gap2(&off) <= self.r2 {
            self.visit(far.0, far.1, off, far.2);
        }
    }
}
