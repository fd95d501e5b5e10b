//! Gather directions drawn after the light the photons brought (Jensen,
//! "Importance driven path tracing using the photon map", 1995): each
//! cache cell of the guide's level (side `8h`) keeps a coarse histogram of
//! the directions its indirect photons arrived from, and the final gather
//! from a diffuse surface draws its directions from that histogram and the
//! cosine.
//!
//! - **Domain**: the unit square of cosine-weighted sampling, `sin^2 theta`
//!   by azimuth over `2 pi`, where the cosine's density is uniform; the
//!   histogram is [`SIDE`] x [`SIDE`] bins of it. A photon's power in a bin
//!   is `integral L cos dw` over the bin's directions: for a diffuse
//!   surface, the gather integrand's mass there.
//! - **Photons**: those of its finest cells' own k-nearest estimates (the
//!   photons they saw, on their side, in their plane) that bounced at least once
//!   and are not caustic photons: the gather counts neither the light's
//!   emission (light sampling does) nor light through mirrors and glass (the
//!   caustic map does).
//! - **Density**: `FLOOR + (1 - FLOOR) x` the histogram's share over each
//!   bin, so every direction keeps a density of at least [`FLOOR`] times the
//!   cosine's: a gather ray's weight `albedo / density` is at most
//!   `1 / FLOOR` times the cosine-sampled one, however wrong the histogram.
//!   The density is exact (the pdf the weight divides by is the one the
//!   direction was drawn from), so the gather stays unbiased; a poor
//!   histogram only costs variance.
//! - **Stratification**: a point of the square is moved by the inverse of
//!   the histogram's piecewise-constant distribution (row, then column), a
//!   monotone map of each coordinate, so the pixel's stratified points stay
//!   stratified.
//! - **Frame**: the normal, and a tangent from a fixed axis chosen by the
//!   geometric normal's dominant axis (the cache's [`bucket`]): continuous over a cell's
//!   normals, unlike a frame built from the normal alone, which turns where
//!   the normal's z changes sign (every wall of a box).
//! - **Storage**: 16 bytes a cell (a bin's power relative to the largest,
//!   8 bits), in a table of its own keyed like the cache's cells.

use super::bucket;
use crate::sampling::{luminance, phi_of, Frame};
use glam::Vec3;
use std::f32::consts::TAU;

/// Bins per side of the histogram's square.
pub const SIDE: usize = 4;
/// Bins of a histogram.
const BINS: usize = SIDE * SIDE;
/// Share of a guide's density spread evenly over the square (see the
/// module docs: it bounds a gather ray's weight at twice the cosine's).
/// On the Cornell box at N_MAX 1e5 and 64 spp, 0.1, 0.25, 0.4, 0.5 and
/// 0.65 gave a relRMSE of 3.40, 3.12, 3.02, 3.03 and 3.03 % (3.33 % with
/// cosine gathers): a sharper guide follows its histogram's noise.
pub const FLOOR: f32 = 0.5;
const ONE_MINUS: f32 = 1.0 - f32::EPSILON / 2.0;

/// A cell's histogram: each bin's power over the largest bin's, in 1/255.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Histogram([u8; BINS]);

/// The guide's frame at a point of geometric normal `ng` and shading
/// normal `n` (both unit, on one side): `n`, and the tangent closest to a
/// fixed axis normal to `ng`'s dominant one.
pub(crate) fn frame(ng: Vec3, n: Vec3) -> Frame {
    // The bucket's dominant axis x, y or z picks y, z or x.
    let axis = [Vec3::Y, Vec3::Z, Vec3::X][bucket(ng) as usize / 2];
    let s = (axis - axis.dot(n) * n).normalize_or_zero();
    if s == Vec3::ZERO {
        return Frame::from_normal(n);
    }
    Frame {
        s,
        t: n.cross(s),
        n,
    }
}

/// Power (luminance) per bin of a histogram, before it is quantised.
pub(super) type PowerPerBin = [f32; BINS];

/// The power per bin of `photons` (direction of travel, power) arriving at
/// a surface whose guide frame is `frame`, those from above it.
pub(super) fn power_per_bin(
    frame: &Frame,
    photons: impl Iterator<Item = (Vec3, Vec3)>,
) -> PowerPerBin {
    let mut power = [0.0f32; BINS];
    for (dir, p) in photons {
        let w = frame.local_from_world(-dir);
        let v = luminance(p);
        if w.z > 0.0 && v > 0.0 && v.is_finite() {
            power[bin_of(w)] += v;
        }
    }
    power
}

/// The bin of a local direction `w` (`w.z > 0`).
fn bin_of(w: Vec3) -> usize {
    let u0 = (w.x * w.x + w.y * w.y).min(ONE_MINUS);
    let i = ((u0 * SIDE as f32) as usize).min(SIDE - 1);
    i * SIDE + azimuth_bin(w)
}

/// The azimuth's bin of `w`: its quadrant, read from the signs of `w.x`
/// and `w.y` where `w` is clear of the quadrants' edges, else from
/// [`phi_of`]. The same bin either way (an `atan2` is within an ulp or two,
/// and the signs are used only a milliradian away from an edge), for a
/// tenth of the cache's build: the build bins every photon of every
/// finest cell's estimate.
fn azimuth_bin(w: Vec3) -> usize {
    const _: () = assert!(SIDE == 4, "the signs give quadrants");
    let (ax, ay) = (w.x.abs(), w.y.abs());
    // Each at least a thousandth of the other (false for a NaN).
    if ax > 1e-3 * ay && ay > 1e-3 * ax {
        return match (w.x > 0.0, w.y > 0.0) {
            (true, true) => 0,
            (false, true) => 1,
            (false, false) => 2,
            (true, false) => 3,
        };
    }
    azimuth_bin_by_angle(w)
}

/// [`azimuth_bin`] by the angle: `floor(SIDE phi / (2 pi))`.
fn azimuth_bin_by_angle(w: Vec3) -> usize {
    let u1 = (phi_of(w) / TAU).min(ONE_MINUS);
    ((u1 * SIDE as f32) as usize).min(SIDE - 1)
}

impl Histogram {
    /// The histogram of the power per bin `power` ([`power_per_bin`]);
    /// `None` when there is none.
    pub(super) fn of(power: &PowerPerBin) -> Option<Self> {
        let top = power.iter().fold(0.0f32, |a, &b| a.max(b));
        if top <= 0.0 || !top.is_finite() {
            return None;
        }
        Some(Histogram(power.map(|p| (p / top * 255.0).round() as u8)))
    }

    /// The guide of this histogram in the frame `frame` ([`frame`]): each
    /// bin's sampling density over the cosine's (mean 1).
    pub(super) fn guide(&self, frame: Frame) -> Guide {
        let total: u32 = self.0.iter().map(|&q| u32::from(q)).sum();
        // The largest bin is 255: total > 0.
        let scale = (1.0 - FLOOR) * BINS as f32 / total.max(1) as f32;
        let density = self.0.map(|q| FLOOR + scale * f32::from(q));
        let mut below = [0.0f32; BINS];
        let mut rows_below = [0.0f32; SIDE + 1];
        for i in 0..SIDE {
            let mut acc = 0.0;
            for j in 0..SIDE {
                below[i * SIDE + j] = acc;
                acc += density[i * SIDE + j];
            }
            rows_below[i + 1] = rows_below[i] + acc;
        }
        Guide {
            density,
            inverse: density.map(|d| 1.0 / d),
            below,
            rows_below,
            row_inverse: std::array::from_fn(|i| 1.0 / (rows_below[i + 1] - rows_below[i])),
            frame,
        }
    }
}

/// Where a diffuse gather draws its directions (Jensen 1995, importance
/// from the photon map): a density over the square of cosine-weighted
/// sampling, `(sin^2 theta, phi / 2 pi)`, per bin of a 4 x 4 histogram of
/// the power of the indirect photons that arrived there, relative to the
/// cosine's: half the cosine's, half the histogram's, so a gather ray's
/// weight is at most twice the cosine-sampled one. The frame is the
/// shading normal with a tangent from a fixed axis normal to the geometric
/// normal's dominant one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Guide {
    density: [f32; BINS],
    /// `1 / density`: a draw multiplies where it would divide (a division's
    /// latency sat on the draw's chain of dependent steps).
    inverse: [f32; BINS],
    /// Each bin's row's density before it.
    below: [f32; BINS],
    /// The rows' density before each row (the last entry: all of it).
    rows_below: [f32; SIDE + 1],
    /// `1 /` each row's density.
    row_inverse: [f32; SIDE],
    frame: Frame,
}

impl Guide {
    /// A direction (world, above the shading normal's plane) from the point
    /// `u` of the unit square, and the inverse of its density relative to
    /// the cosine's: the pdf is `cos(theta) / (pi inverse)`, and a diffuse
    /// gather ray's weight the albedo times `inverse`.
    #[inline]
    pub fn sample(&self, [u0, u1]: [f32; 2]) -> (Vec3, f32) {
        // The row, then the column in it, by counting the bounds below the
        // point: no branch to mispredict on random points. Each bound
        // counted is at most the point, so the offsets are >= 0.
        let x = u0 * self.rows_below[SIDE];
        let i = (1..SIDE).filter(|&k| x >= self.rows_below[k]).count();
        let t0 = ((x - self.rows_below[i]) * self.row_inverse[i]).min(ONE_MINUS);
        let y = u1 * (self.rows_below[i + 1] - self.rows_below[i]);
        let below = &self.below[i * SIDE..(i + 1) * SIDE];
        let j = (1..SIDE).filter(|&k| y >= below[k]).count();
        let bin = i * SIDE + j;
        let t1 = ((y - below[j]) * self.inverse[bin]).min(ONE_MINUS);
        let a = (i as f32 + t0) * (1.0 / SIDE as f32);
        let b = (j as f32 + t1) * (1.0 / SIDE as f32);
        let sin = a.sqrt();
        let cos = (1.0 - a).max(0.0).sqrt();
        let (s, c) = (TAU * b).sin_cos();
        let local = Vec3::new(sin * c, sin * s, cos);
        (self.frame.world_from_local(local), self.inverse[bin])
    }

    /// The density relative to the cosine's of the world direction `w`
    /// (above the shading normal's plane).
    pub fn density(&self, w: Vec3) -> f32 {
        self.density[bin_of(self.frame.local_from_world(w))]
    }
}

/// The cells' histograms, keyed like the cache's cells: open
/// addressing, a 32-bit tag of the key beside the 16 bytes.
#[derive(Default)]
pub(super) struct GuideTable {
    tags: Vec<u32>,
    bins: Vec<[u8; BINS]>,
    len: usize,
}

impl GuideTable {
    /// The table of `entries` (key, histogram), at most 2/3 full.
    pub(super) fn new(entries: &[(u64, Histogram)]) -> Self {
        let slots = (entries.len() + entries.len().div_ceil(2)).max(1);
        let mut t = GuideTable {
            tags: vec![0; slots],
            bins: vec![[0; BINS]; slots],
            len: entries.len(),
        };
        for (key, h) in entries {
            let mut i = t.home(*key);
            while t.tags[i] != 0 {
                i = if i + 1 == slots { 0 } else { i + 1 };
            }
            t.tags[i] = tag(*key);
            t.bins[i] = h.0;
        }
        t
    }

    fn home(&self, key: u64) -> usize {
        ((key as u32 as u64 * self.tags.len() as u64) >> 32) as usize
    }

    /// The histogram of the cell `key`, if it has one.
    pub(super) fn get(&self, key: u64) -> Option<Histogram> {
        let t = tag(key);
        let mut i = self.home(key);
        loop {
            let s = *self.tags.get(i)?;
            if s == t {
                return Some(Histogram(self.bins[i]));
            }
            if s == 0 {
                return None;
            }
            i = if i + 1 == self.tags.len() { 0 } else { i + 1 };
        }
    }

    /// Histograms held.
    pub(super) fn len(&self) -> usize {
        self.len
    }

    /// Bytes held.
    pub(super) fn bytes(&self) -> usize {
        self.tags.len() * (4 + BINS)
    }
}

/// A key's tag in the table, never 0.
fn tag(key: u64) -> u32 {
    (key >> 32) as u32 | 1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// The quadrant by the signs is the angle's bin: for random directions,
    /// for directions a hair off each axis (both sides, at many scales),
    /// for the axes themselves and their signed zeros, and for NaN and
    /// infinite components.
    #[test]
    fn the_azimuths_bin_by_signs_is_the_angles() {
        let mut rng = Rng::new(17);
        let mut dirs: Vec<Vec3> = (0..100_000)
            .map(|_| {
                let [a, b] = rng.next_2d();
                Vec3::new(2.0 * a - 1.0, 2.0 * b - 1.0, 0.5)
            })
            .collect();
        for e in 0..40 {
            let hair = 2f32.powi(-e);
            for (big, small) in [(1.0f32, hair), (hair, 1.0)] {
                for (sx, sy) in [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)] {
                    dirs.push(Vec3::new(sx * big, sy * small, 0.5));
                    // Just either side of the shortcut's 1e-3 threshold.
                    let edge = 1e-3 * big.max(small);
                    for t in [edge * 0.999_99, edge * 1.000_01] {
                        dirs.push(Vec3::new(sx * big.max(small), sy * t, 0.5));
                        dirs.push(Vec3::new(sx * t, sy * big.max(small), 0.5));
                    }
                }
            }
        }
        for x in [0.0f32, -0.0, 1.0, -1.0, f32::NAN, f32::INFINITY] {
            for y in [0.0f32, -0.0, 1.0, -1.0, f32::NAN, f32::NEG_INFINITY] {
                dirs.push(Vec3::new(x, y, 0.5));
            }
        }
        for w in dirs {
            assert_eq!(azimuth_bin(w), azimuth_bin_by_angle(w), "{w:?}");
        }
    }

    const LOCAL: Frame = Frame {
        s: Vec3::X,
        t: Vec3::Y,
        n: Vec3::Z,
    };

    fn guide_of(bytes: [u8; BINS]) -> Guide {
        Histogram(bytes).guide(LOCAL)
    }

    /// The directions drawn follow `density cos / pi`: the share of draws in
    /// each bin is the bin's density over the bins' sum, within 4 sigma of
    /// the multinomial noise, and the density returned is the bin's.
    #[test]
    fn draws_follow_the_density_they_report() {
        let mut rng = Rng::new(7);
        let bytes: [u8; BINS] = std::array::from_fn(|b| (b * 37 % 256) as u8);
        let g = guide_of(bytes);
        let n = 200_000;
        let mut count = [0u32; BINS];
        for _ in 0..n {
            let (w, inverse) = g.sample(rng.next_2d());
            assert!((w.length() - 1.0).abs() < 1e-5 && w.z >= 0.0, "{w}");
            let b = bin_of(w);
            assert_eq!(inverse, 1.0 / g.density[b]);
            assert_eq!(g.density(w), g.density[b]);
            count[b] += 1;
        }
        let sum: f32 = g.density.iter().sum();
        for (b, (&d, &c)) in g.density.iter().zip(&count).enumerate() {
            let p = (d / sum) as f64;
            let sigma = (n as f64 * p * (1.0 - p)).sqrt();
            let got = c as f64;
            assert!(
                (got - n as f64 * p).abs() <= 4.0 * sigma,
                "bin {b}: {got} for {}",
                n as f64 * p
            );
        }
        assert!((sum / BINS as f32 - 1.0).abs() < 1e-5, "{sum}");
    }

    /// A gather drawn by the guide estimates the same integral as the
    /// cosine: the mean of `f(w) / density(w)` over guided draws is the
    /// cosine-weighted mean of `f`, within 4 sigma of its own noise.
    #[test]
    fn a_guided_estimate_is_unbiased() {
        let f = |w: Vec3| if w.x > 0.3 { 5.0 } else { 0.2 + w.y * w.y };
        let mut rng = Rng::new(11);
        let n = 400_000;
        let (mut c1, mut c2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let [a, b] = rng.next_2d();
            let (s, c) = (TAU * b).sin_cos();
            let w = Vec3::new(a.sqrt() * c, a.sqrt() * s, (1.0 - a).sqrt());
            let v = f(w) as f64;
            c1 += v;
            c2 += v * v;
        }
        let cosine = c1 / n as f64;
        let var_cosine = (c2 / n as f64 - cosine * cosine) / n as f64;
        let frame = LOCAL;
        let photons = (0..2000).map(|k| {
            let phi = k as f32 * 0.01;
            (-Vec3::new(0.8 * phi.cos(), 0.8 * phi.sin(), 0.6), Vec3::ONE)
        });
        let g = Histogram::of(&power_per_bin(&frame, photons))
            .unwrap()
            .guide(LOCAL);
        let (mut s1, mut s2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let (w, inverse) = g.sample(rng.next_2d());
            let v = (f(w) * inverse) as f64;
            s1 += v;
            s2 += v * v;
        }
        let mean = s1 / n as f64;
        let var_guided = (s2 / n as f64 - mean * mean) / n as f64;
        let sigma = (var_guided + var_cosine).sqrt();
        assert!(
            (mean - cosine).abs() <= 4.0 * sigma,
            "{mean} against {cosine} (sigma {sigma})"
        );
    }

    /// Every density is at least the floor, and a histogram of one bin puts
    /// the rest of the mass there.
    #[test]
    fn the_floor_bounds_the_weight() {
        let mut bytes = [0u8; BINS];
        bytes[5] = 255;
        let g = guide_of(bytes);
        for b in 0..BINS {
            let want = if b == 5 {
                FLOOR + (1.0 - FLOOR) * BINS as f32
            } else {
                FLOOR
            };
            assert!((g.density[b] - want).abs() < 1e-5, "{b}: {}", g.density[b]);
        }
    }

    /// The frame is orthonormal with the shading normal as z, and the same
    /// for normals of one dominant axis whichever sign their other
    /// components take.
    #[test]
    fn the_frame_is_orthonormal_and_continuous() {
        let mut rng = Rng::new(3);
        for _ in 0..1000 {
            let [a, b] = rng.next_2d();
            let n = Vec3::new(a - 0.5, 1.0, b - 0.5).normalize();
            let f = frame(n, n);
            for (x, y) in [(f.s, f.t), (f.t, f.n), (f.s, f.n)] {
                assert!(x.dot(y).abs() < 1e-5);
            }
            assert!((f.s.length() - 1.0).abs() < 1e-5 && (f.t.length() - 1.0).abs() < 1e-5);
            assert!(f.s.z > 0.8, "{n}: {}", f.s);
        }
        let (p, m) = (Vec3::new(1.0, 0.0, 1e-7), Vec3::new(1.0, 0.0, -1e-7));
        let (fp, fm) = (
            frame(p.normalize(), p.normalize()),
            frame(m.normalize(), m.normalize()),
        );
        assert!((fp.s - fm.s).length() < 1e-5);
    }

    /// Keys read back their histograms; others miss.
    #[test]
    fn the_table_reads_back() {
        let entries: Vec<(u64, Histogram)> = (0..500u64)
            .map(|k| {
                let key = crate::rng::mix64(k + 1);
                (key, Histogram([k as u8; BINS]))
            })
            .collect();
        let t = GuideTable::new(&entries);
        for (key, h) in &entries {
            assert_eq!(t.get(*key), Some(*h));
        }
        for k in 1000..1500u64 {
            assert_eq!(t.get(crate::rng::mix64(k << 20)), None);
        }
    }
}
