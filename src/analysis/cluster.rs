//! Step 3: greedy agglomerative clustering with complete linkage (paper
//! §2.1.3; docs/method.md, "Step 3: clustering").
//!
//! Only one group grows at a time: every other group is still a single
//! sample. So the complete-linkage distance of the growing group G to a
//! sample k, `max_{i in G} angle(i, k)`, is kept in one array and updated in
//! O(m) after each merge (`d(G ∪ {j}, k) = max(d(G, k), d(j, k))`, the
//! Lance–Williams rule for complete linkage). Each merge is O(m), each sample
//! is merged at most once, so the whole clustering is **O(m^2) time and
//! O(m) memory**, m the number of samples above the diffuse level (at most
//! the sample count), instead of the O(m^3) of recomputing linkages. Angles
//! are compared through dot products (acos is monotone).
//!
//! Samples at or below the diffuse level `1 / (2 pi)` never seed nor join a
//! group (otherwise the last peak swallows the low tail: docs/method.md,
//! "Step 3: clustering").

use glam::Vec3;

/// The hemisphere mean of a unit-integral function: `1 / (2 pi)` sr^-1.
pub const DIFFUSE_LEVEL: f32 = 1.0 / (2.0 * std::f32::consts::PI);

/// Clusters `(dirs[i], values[i])` into groups of sample indices, in the
/// order they were set aside (highest seed value first).
///
/// `variance_limit` is the absolute bound on the variance of values inside a
/// group (the caller passes 15 % of the global variance). Ties between
/// equally near samples go to the lower index, so the result is
/// deterministic. Directions are unit vectors (a non-finite one leaves its
/// sample in a group of its own or in none, never a panic).
///
/// # Panics
/// Never; `dirs` and `values` of different lengths are truncated to the
/// shorter.
pub fn cluster(dirs: &[Vec3], values: &[f32], variance_limit: f64) -> Vec<Vec<u32>> {
    cluster_in(&mut Live::default(), dirs, values, variance_limit)
}

/// [`cluster`] in the buffers of `c`, which a caller clustering many sample
/// sets keeps from one to the next (an analysis clusters 24 to 48; their
/// allocations were a twentieth of it).
pub(crate) fn cluster_in(
    c: &mut Live,
    dirs: &[Vec3],
    values: &[f32],
    variance_limit: f64,
) -> Vec<Vec<u32>> {
    c.fill(dirs, values);
    let mut groups = Vec::new();
    // The growing group, in one buffer for all of them: each group is
    // copied out at its size (no regrowth, and O(m) memory in all).
    let mut group = std::mem::take(&mut c.group);
    while c.len > 0 {
        let seed = c.seed();
        let (sv, s) = (c.v[seed], c.dir(seed));
        group.clear();
        group.push(c.id[seed]);
        c.remove(seed);
        let (mut s1, mut s2) = (sv as f64, sv as f64 * sv as f64);
        let mut best = c.update(s, true);
        while let Some(b) = best {
            let v = c.v[b] as f64;
            let n = group.len() as f64 + 1.0;
            let (t1, t2) = (s1 + v, s2 + v * v);
            if t2 / n - (t1 / n) * (t1 / n) > variance_limit {
                break;
            }
            s1 = t1;
            s2 = t2;
            group.push(c.id[b]);
            let d = c.dir(b);
            c.remove(b);
            best = c.update(d, false);
        }
        groups.push(group.clone());
    }
    c.group = group;
    groups
}

/// Lanes per block of [`Live`]: two SSE registers, or one AVX register.
const L: usize = 8;

/// A block of `L` lanes.
type Block = [f32; L];

/// The samples not yet in a group, as a struct of arrays of `L`-lane blocks
/// whose first `len` lanes are alive (removal swaps with the last alive
/// lane), so every pass touches only live samples, and fixed-size blocks
/// let the compiler vectorise it without bounds checks.
#[derive(Debug, Default)]
pub(crate) struct Live {
    x: Vec<Block>,
    y: Vec<Block>,
    z: Vec<Block>,
    /// Cosine of the complete-linkage angle to the growing group.
    min_dot: Vec<Block>,
    v: Vec<f32>,
    id: Vec<u32>,
    len: usize,
    /// The buffer of [`cluster_in`]'s growing group.
    group: Vec<u32>,
}

fn lane(a: &[Block], k: usize) -> f32 {
    a[k / L][k % L]
}

/// One block of the linkage: `min(m, d . w)` per lane (`d . w` alone when
/// `reset`), written one step per loop over the lanes, the form that the
/// compiler turns into vector instructions (one loop of every step per lane
/// stayed scalar). `min` is written without its NaN case (there is none),
/// so that it is one instruction.
#[inline(always)]
fn link(m: &Block, [x, y, z]: [&Block; 3], d: Vec3, reset: bool) -> Block {
    let mut dot = [0.0f32; L];
    for j in 0..L {
        dot[j] = d.x * x[j] + d.y * y[j] + d.z * z[j];
    }
    if !reset {
        for j in 0..L {
            dot[j] = if dot[j] < m[j] { dot[j] } else { m[j] };
        }
    }
    dot
}

/// Each lane's running maximum raised by `values` (one per lane, at most
/// `L`), as a select the compiler vectorises (no NaN case to handle: the
/// values compared are never NaN, or a NaN never wins).
#[inline(always)]
fn raise_lanes(lanes: &mut Block, values: &[f32]) {
    for (l, &v) in lanes.iter_mut().zip(values) {
        *l = if v > *l { v } else { *l };
    }
}

/// The largest of `values` (-inf for none; a NaN never wins).
fn largest<'a>(values: impl IntoIterator<Item = &'a f32>) -> f32 {
    values
        .into_iter()
        .fold(f32::NEG_INFINITY, |a, &b| if b > a { b } else { a })
}

impl Live {
    /// Takes the samples above the diffuse level of `(dirs, values)`,
    /// in the buffers of the last set. The lanes past `len` are left as
    /// they are: no pass reads them (the last block's are set to -inf).
    fn fill(&mut self, dirs: &[Vec3], values: &[f32]) {
        let n = dirs.len().min(values.len());
        let blocks = n.div_ceil(L);
        for a in [&mut self.x, &mut self.y, &mut self.z, &mut self.min_dot] {
            a.clear();
            a.resize(blocks, [0.0; L]);
        }
        self.v.clear();
        self.id.clear();
        for i in 0..n {
            if values[i] > DIFFUSE_LEVEL {
                let k = self.id.len();
                self.x[k / L][k % L] = dirs[i].x;
                self.y[k / L][k % L] = dirs[i].y;
                self.z[k / L][k % L] = dirs[i].z;
                self.v.push(values[i]);
                self.id.push(i as u32);
            }
        }
        self.len = self.id.len();
    }

    /// The highest-valued live sample, ties to the lowest id: it seeds the
    /// next group. The maximum over `L` lanes first, then the ids of the
    /// samples that reach it (a scan per group, as there are few groups;
    /// one compare-and-branch per sample was a tenth of the analysis, by
    /// its mispredictions).
    fn seed(&self) -> usize {
        let v = &self.v[..self.len];
        let mut lanes = [f32::NEG_INFINITY; L];
        let mut chunks = v.chunks_exact(L);
        for c in &mut chunks {
            raise_lanes(&mut lanes, c);
        }
        let top = largest(chunks.remainder().iter().chain(&lanes));
        let mut seed: Option<usize> = None;
        for (k, &value) in v.iter().enumerate() {
            if value == top && seed.is_none_or(|s| self.id[k] < self.id[s]) {
                seed = Some(k);
            }
        }
        // Values are above the diffuse level, so never NaN: one reaches the
        // top.
        seed.unwrap_or(0)
    }

    fn dir(&self, k: usize) -> Vec3 {
        Vec3::new(lane(&self.x, k), lane(&self.y, k), lane(&self.z, k))
    }

    fn remove(&mut self, k: usize) {
        let last = self.len - 1;
        // Flat views: one bounds check per swap, no lane arithmetic.
        self.x.as_flattened_mut().swap(k, last);
        self.y.as_flattened_mut().swap(k, last);
        self.z.as_flattened_mut().swap(k, last);
        self.min_dot.as_flattened_mut().swap(k, last);
        self.v.swap(k, last);
        self.id.swap(k, last);
        self.len = last;
    }

    /// Folds the new member `d` into the linkage (`reset`: `d` is the seed)
    /// and returns the nearest live sample, ties to the lowest id.
    fn update(&mut self, d: Vec3, reset: bool) -> Option<usize> {
        let n = self.len;
        if n == 0 {
            return None;
        }
        // The linkage and the largest min-dot in one pass over the blocks:
        // the full blocks, then the last one, whose lanes past `len` are
        // set to -inf so that they are never the largest (a min-dot is never
        // NaN: unit vectors).
        let (full, tail) = (n / L, n % L);
        let blocks = n.div_ceil(L);
        let (x, y, z) = (&self.x[..blocks], &self.y[..blocks], &self.z[..blocks]);
        let md = &mut self.min_dot[..blocks];
        let mut lanes = [f32::NEG_INFINITY; L];
        for b in 0..full {
            md[b] = link(&md[b], [&x[b], &y[b], &z[b]], d, reset);
            raise_lanes(&mut lanes, &md[b]);
        }
        if tail > 0 {
            let mut linked = link(&md[full], [&x[full], &y[full], &z[full]], d, reset);
            linked[tail..].fill(f32::NEG_INFINITY);
            md[full] = linked;
            raise_lanes(&mut lanes, &linked);
        }
        let top = largest(&lanes);
        self.lowest_id_at(top)
    }

    /// The live sample of min-dot `top` with the lowest id (ties are rare),
    /// looked up in the blocks that hold it (a vectorised test per block),
    /// by the bit mask of their lanes at `top` (a scalar test of each lane
    /// of a hit block was a sixth of the clustering).
    fn lowest_id_at(&self, top: f32) -> Option<usize> {
        let n = self.len;
        let mut best: Option<usize> = None;
        for (b, m) in self.min_dot[..n.div_ceil(L)].iter().enumerate() {
            if !m.iter().fold(false, |hit, &v| hit | (v == top)) {
                continue;
            }
            let mut hits = lanes_at(m, top);
            while hits != 0 {
                let k = b * L + hits.trailing_zeros() as usize;
                hits &= hits - 1;
                // `k < n`: when no live min-dot beats -inf (NaN from a
                // non-finite direction), a dead lane's -inf is the top.
                if k < n && best.is_none_or(|bk| self.id[k] < self.id[bk]) {
                    best = Some(k);
                }
            }
        }
        best
    }
}

/// Bit `j` set when lane `j` of `m` equals `top`.
#[inline(always)]
fn lanes_at(m: &Block, top: f32) -> u32 {
    let mut mask = 0u32;
    for (j, &v) in m.iter().enumerate() {
        mask |= u32::from(v == top) << j;
    }
    mask
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use crate::sampling::uniform_hemisphere;

    /// The definition, literally: complete-linkage distance recomputed from
    /// the members at every step (O(m^3)).
    fn brute(dirs: &[Vec3], values: &[f32], limit: f64) -> Vec<Vec<u32>> {
        let mut left: Vec<u32> = (0..dirs.len() as u32)
            .filter(|&i| values[i as usize] > DIFFUSE_LEVEL)
            .collect();
        let mut groups = Vec::new();
        while !left.is_empty() {
            let seed = *left
                .iter()
                .max_by(|&&a, &&b| {
                    values[a as usize]
                        .total_cmp(&values[b as usize])
                        .then(b.cmp(&a))
                })
                .unwrap();
            left.retain(|&i| i != seed);
            let mut g = vec![seed];
            loop {
                let link = |k: u32| {
                    g.iter()
                        .map(|&i| dirs[i as usize].dot(dirs[k as usize]))
                        .fold(f32::INFINITY, f32::min)
                };
                let Some(&b) = left
                    .iter()
                    .max_by(|&&a, &&b| link(a).total_cmp(&link(b)).then(b.cmp(&a)))
                else {
                    break;
                };
                let vals: Vec<f64> = g
                    .iter()
                    .chain(std::iter::once(&b))
                    .map(|&i| values[i as usize] as f64)
                    .collect();
                let n = vals.len() as f64;
                let m = vals.iter().sum::<f64>() / n;
                let var = vals.iter().map(|v| v * v).sum::<f64>() / n - m * m;
                if var > limit {
                    break;
                }
                left.retain(|&i| i != b);
                g.push(b);
            }
            groups.push(g);
        }
        groups
    }

    #[test]
    fn fast_equals_brute_force() {
        for seed in 0..4u64 {
            let mut r = Rng::new(seed);
            let dirs: Vec<Vec3> = (0..150).map(|_| uniform_hemisphere(r.next_2d())).collect();
            let values: Vec<f32> = dirs
                .iter()
                .map(|d| 3.0 * d.z.powi(8) + (-(d.x - 0.6).powi(2) * 20.0).exp() + 0.05)
                .collect();
            for limit in [0.01, 0.1, 1.0] {
                assert_eq!(cluster(&dirs, &values, limit), brute(&dirs, &values, limit));
            }
        }
    }

    /// The 8-lane blocks at their edges: no sample, fewer than a block, whole
    /// blocks and one past them, ties of equal values and directions.
    #[test]
    fn fast_equals_brute_force_at_block_edges() {
        let mut r = Rng::new(9);
        for n in [0usize, 1, 2, 7, 8, 9, 15, 16, 17, 24, 33] {
            let mut dirs: Vec<Vec3> = (0..n).map(|_| uniform_hemisphere(r.next_2d())).collect();
            let mut values: Vec<f32> = dirs.iter().map(|d| 0.2 + d.z * d.z).collect();
            if n > 3 {
                // Ties: a duplicated sample, and an equal value elsewhere.
                dirs[n - 1] = dirs[0];
                values[n - 1] = values[0];
                values[n - 2] = values[1];
            }
            for limit in [0.001, 0.05, 1.0] {
                assert_eq!(
                    cluster(&dirs, &values, limit),
                    brute(&dirs, &values, limit),
                    "n {n}"
                );
            }
        }
    }

    /// A non-finite direction never panics nor puts a sample in two groups.
    #[test]
    fn non_finite_directions_do_not_break_the_groups() {
        let mut r = Rng::new(3);
        for bad in [Vec3::NAN, Vec3::new(f32::INFINITY, 0.0, 1.0)] {
            for n in [1usize, 5, 8, 13] {
                let mut dirs: Vec<Vec3> = (0..n).map(|_| uniform_hemisphere(r.next_2d())).collect();
                let values = vec![0.5; n];
                for k in 0..n {
                    dirs[k] = bad;
                    let groups = cluster(&dirs, &values, 1.0);
                    let mut ids: Vec<u32> = groups.concat();
                    ids.sort_unstable();
                    let len = ids.len();
                    ids.dedup();
                    assert_eq!(ids.len(), len, "a sample in two groups: n {n}, bad {bad}");
                    assert!(ids.iter().all(|&i| (i as usize) < n));
                }
            }
        }
    }
}
