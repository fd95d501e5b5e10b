//! Stratified sample points for the pixels: a padded, scrambled (0,2)-sequence.
//!
//! Each 2D decision of a camera sample (the position in the pixel, a light
//! sample, a gather direction) is its own *dimension pair*. For pair `d`, the
//! `n` points of a pixel are the first `n` points of the (0,2)-sequence (the
//! first two Sobol dimensions: van der Corput and its Pascal-matrix partner),
//! shifted by a random XOR per pixel and pair (a digital shift keeps the
//! (0,m,2)-net strata), and visited in an order permuted per pixel and pair
//! (Kensler's hashed permutation, "Correlated multi-jittered sampling", 2013),
//! so that the pairs of one sample are not correlated with each other. This is
//! the construction of pbrt-v4's padded Sobol sampler, written from its
//! description.
//!
//! For `n` a power of two every elementary interval of area `1/n` holds one
//! point: a light sampled with it over a pixel's 64 samples sees 64 strata of
//! its area instead of 64 independent points.

use crate::rng::{hash2, mix64};

/// Dimension pairs used by the renderer.
pub mod dim {
    /// The position in the pixel.
    pub const PIXEL: u32 = 0;
    /// The light samples at the first hit.
    pub const LIGHT: u32 = 1;
    /// The final-gather directions at the first hit.
    pub const GATHER: u32 = 2;
    /// The point inside the piece a light sample on a textured light picked
    /// (the piece takes [`LIGHT`]'s first coordinate, whose bits left over
    /// would place the point on a lattice of a few positions).
    pub const LIGHT_POINT: u32 = 3;
}

/// Pairs whose hashes a sampler computes once, not per point: the
/// renderer's four ([`dim`]).
const CACHED_PAIRS: usize = 4;

/// The stratified points of one pixel.
#[derive(Clone, Copy, Debug)]
pub struct PixelSampler {
    key: u64,
    /// `hash2(key, pair)` of the pairs below [`CACHED_PAIRS`].
    hashes: [u64; CACHED_PAIRS],
}

impl PixelSampler {
    /// The sampler of the pixel whose key is `key` (a hash of seed and pixel).
    pub fn new(key: u64) -> Self {
        PixelSampler {
            key,
            hashes: std::array::from_fn(|d| hash2(key, d as u64)),
        }
    }

    /// Point `i` of `n` (`i < n`) of dimension pair `pair`, in `[0, 1)^2`.
    pub fn get_2d(&self, pair: u32, i: u32, n: u32) -> [f32; 2] {
        let h = match self.hashes.get(pair as usize) {
            Some(&h) => h,
            None => hash2(self.key, pair as u64),
        };
        let index = permute(i, n.max(1), h as u32);
        let (a, b) = sobol02(index);
        let s = mix64(h);
        [unit(a ^ s as u32), unit(b ^ (s >> 32) as u32)]
    }
}

/// 32 bits to `[0, 1)` (24 bits, never 1).
#[inline]
fn unit(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Point `i` of the (0,2)-sequence, as 32-bit fractions.
#[inline]
pub fn sobol02(mut i: u32) -> (u32, u32) {
    let a = i.reverse_bits();
    let mut b = 0u32;
    let mut v = 1u32 << 31;
    while i != 0 {
        if i & 1 != 0 {
            b ^= v;
        }
        i >>= 1;
        v ^= v >> 1;
    }
    (a, b)
}

/// A permutation of `0..len` chosen by `p`, evaluated at `i` (Kensler 2013:
/// a hashed bijection on the next power of two, cycle-walked into range).
pub fn permute(mut i: u32, len: u32, p: u32) -> u32 {
    if len <= 1 {
        return 0;
    }
    let mut w = len - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    loop {
        i ^= p;
        i = i.wrapping_mul(0xe170_893d);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929_eb3f);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | (p >> 27));
        i = i.wrapping_mul(0x6935_fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dc_b303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e50_1cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860_a3df);
        i &= w;
        i ^= i >> 5;
        if i < len {
            break;
        }
    }
    ((i as u64 + p as u64) % len as u64) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permutation_is_a_bijection() {
        for len in [1u32, 2, 3, 7, 64, 100] {
            let mut seen = vec![false; len as usize];
            for i in 0..len {
                let j = permute(i, len, 0xDEAD_BEEF);
                assert!(!seen[j as usize], "len {len}: {j} twice");
                seen[j as usize] = true;
            }
        }
    }

    /// 64 points: one in each of the 8 x 8 cells, and in each 64 x 1 and 1 x 64 strip.
    #[test]
    fn a_pixel_of_64_points_is_a_0_6_2_net() {
        let s = PixelSampler::new(42);
        for (nx, ny) in [(8usize, 8usize), (64, 1), (1, 64), (16, 4), (2, 32)] {
            let mut seen = [false; 64];
            for i in 0..64 {
                let [x, y] = s.get_2d(dim::LIGHT, i, 64);
                let c = (y * ny as f32) as usize * nx + (x * nx as f32) as usize;
                assert!(!seen[c], "{nx}x{ny}: cell {c} twice");
                seen[c] = true;
            }
        }
    }

    /// The mean of a smooth function converges much faster than 1/sqrt(n).
    #[test]
    fn stratified_mean_beats_independent_points() {
        let f = |[x, y]: [f32; 2]| (x * 6.0).sin() * y * y + x;
        let exact = {
            // integral of sin(6x) dx y^2 dy + 1/2 = (1 - cos 6)/6 / 3 + 1/2
            (1.0 - 6.0f64.cos()) / 18.0 + 0.5
        };
        let mut worst = 0.0f64;
        for pixel in 0..50u64 {
            let s = PixelSampler::new(hash2(7, pixel));
            let m: f64 = (0..64)
                .map(|i| f(s.get_2d(dim::GATHER, i, 64)) as f64)
                .sum::<f64>()
                / 64.0;
            worst = worst.max((m - exact).abs());
        }
        // Independent points: sd ~ 0.33 / 8 = 0.04; the net stays far below.
        assert!(worst < 0.01, "worst error {worst}");
    }
}
