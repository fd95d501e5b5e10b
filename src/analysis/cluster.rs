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
/// deterministic.
///
/// # Panics
/// Never; `dirs` and `values` of different lengths are truncated to the
/// shorter.
pub fn cluster(dirs: &[Vec3], values: &[f32], variance_limit: f64) -> Vec<Vec<u32>> {
    let mut c = Live::new(dirs, values);
    let mut groups = Vec::new();
    while c.len > 0 {
        // The highest-valued sample left seeds the next group.
        let mut seed = 0;
        for k in 1..c.len {
            if c.v[k] > c.v[seed] || (c.v[k] == c.v[seed] && c.id[k] < c.id[seed]) {
                seed = k;
            }
        }
        let (sv, s) = (c.v[seed], c.dir(seed));
        let mut group = vec![c.id[seed]];
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
        groups.push(group);
    }
    groups
}

/// The samples not yet in a group, as a struct of arrays whose first `len`
/// entries are alive (removal swaps with the last alive entry), so every pass
/// touches only live samples and vectorises.
struct Live {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    v: Vec<f32>,
    id: Vec<u32>,
    /// Cosine of the complete-linkage angle to the growing group.
    min_dot: Vec<f32>,
    len: usize,
}

impl Live {
    fn new(dirs: &[Vec3], values: &[f32]) -> Self {
        let n = dirs.len().min(values.len());
        let mut l = Live {
            x: Vec::with_capacity(n),
            y: Vec::with_capacity(n),
            z: Vec::with_capacity(n),
            v: Vec::with_capacity(n),
            id: Vec::with_capacity(n),
            min_dot: Vec::new(),
            len: 0,
        };
        for i in 0..n {
            if values[i] > DIFFUSE_LEVEL {
                l.x.push(dirs[i].x);
                l.y.push(dirs[i].y);
                l.z.push(dirs[i].z);
                l.v.push(values[i]);
                l.id.push(i as u32);
            }
        }
        l.len = l.id.len();
        l.min_dot = vec![0.0; l.len];
        l
    }

    fn dir(&self, k: usize) -> Vec3 {
        Vec3::new(self.x[k], self.y[k], self.z[k])
    }

    fn remove(&mut self, k: usize) {
        let last = self.len - 1;
        self.x.swap(k, last);
        self.y.swap(k, last);
        self.z.swap(k, last);
        self.v.swap(k, last);
        self.id.swap(k, last);
        self.min_dot.swap(k, last);
        self.len = last;
    }

    /// Folds the new member `d` into the linkage (`reset`: `d` is the seed)
    /// and returns the nearest live sample, ties to the lowest id.
    fn update(&mut self, d: Vec3, reset: bool) -> Option<usize> {
        const L: usize = 8;
        let n = self.len;
        let (x, y, z) = (&self.x[..n], &self.y[..n], &self.z[..n]);
        let md = &mut self.min_dot[..n];
        for k in 0..n {
            let dot = d.x * x[k] + d.y * y[k] + d.z * z[k];
            md[k] = if reset { dot } else { md[k].min(dot) };
        }
        // The largest min-dot first, in a reduction over 8 lanes that the
        // compiler vectorises (a min-dot is never NaN: unit vectors), then
        // the lowest id among the samples that reach it (ties are rare), in
        // the 8-sample chunks that hold one (a vectorised count per chunk:
        // a scalar test of every sample was a third of the clustering).
        let mut lanes = [f32::NEG_INFINITY; L];
        let mut chunks = md.chunks_exact(L);
        for c in &mut chunks {
            for j in 0..L {
                lanes[j] = if c[j] > lanes[j] { c[j] } else { lanes[j] };
            }
        }
        let top = chunks
            .remainder()
            .iter()
            .chain(&lanes)
            .fold(f32::NEG_INFINITY, |a, &b| if b > a { b } else { a });
        let mut best: Option<usize> = None;
        let mut consider = |k: usize| {
            if md[k] == top && best.is_none_or(|b| self.id[k] < self.id[b]) {
                best = Some(k);
            }
        };
        for (c, chunk) in md.chunks_exact(L).enumerate() {
            let hits: u32 = chunk.iter().map(|&m| u32::from(m == top)).sum();
            if hits > 0 {
                (c * L..(c + 1) * L).for_each(&mut consider);
            }
        }
        (n - n % L..n).for_each(consider);
        best
    }
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
}
