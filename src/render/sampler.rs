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
    /// The scrambles of the pairs below [`CACHED_PAIRS`]: a sampler is made
    /// once per pixel and asked for several points per sample.
    scrambles: [Scramble; CACHED_PAIRS],
}

/// What randomises one dimension pair of one pixel: the permutation's seed
/// (`hash`, whose low 32 bits pick the order) and the digital shift
/// (`mix64(hash)`, 32 bits per coordinate).
#[derive(Clone, Copy, Debug)]
struct Scramble {
    hash: u64,
    shift: u64,
}

impl Scramble {
    fn new(key: u64, pair: u32) -> Self {
        let hash = hash2(key, pair as u64);
        Scramble {
            hash,
            shift: mix64(hash),
        }
    }
}

impl PixelSampler {
    /// The sampler of the pixel whose key is `key` (a hash of seed and pixel).
    pub fn new(key: u64) -> Self {
        PixelSampler {
            key,
            scrambles: std::array::from_fn(|d| Scramble::new(key, d as u32)),
        }
    }

    /// Point `i` of `n` (`i < n`) of dimension pair `pair`, in `[0, 1)^2`.
    pub fn get_2d(&self, pair: u32, i: u32, n: u32) -> [f32; 2] {
        let sc = match self.scrambles.get(pair as usize) {
            Some(&sc) => sc,
            None => Scramble::new(self.key, pair),
        };
        let index = permute(i, n.max(1), sc.hash as u32);
        let (a, b) = sobol02(index);
        let s = sc.shift;
        [unit(a ^ s as u32), unit(b ^ (s >> 32) as u32)]
    }
}

/// 32 bits to `[0, 1)` (24 bits, never 1).
#[inline]
fn unit(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Point `i` of the (0,2)-sequence, as 32-bit fractions: van der Corput
/// (the bits reversed) and the Pascal matrix's product, a byte at a time.
#[inline]
pub fn sobol02(i: u32) -> (u32, u32) {
    let [b0, b1, b2, b3] = i.to_le_bytes();
    let b = PASCAL_BYTES[0][b0 as usize]
        ^ PASCAL_BYTES[1][b1 as usize]
        ^ PASCAL_BYTES[2][b2 as usize]
        ^ PASCAL_BYTES[3][b3 as usize];
    (i.reverse_bits(), b)
}

/// The second dimension's generator matrix (Pascal's triangle mod 2, its
/// columns `v_0 = 2^31`, `v_(j+1) = v_j ^ (v_j >> 1)`) applied to one byte
/// of the index: entry `[k][x]` is the XOR of the columns of the bits set
/// in `x << 8k`. A bit-by-bit loop branches on every bit, and its
/// mispredictions were a tenth of the render's time (`perf`, 2026-12-05).
static PASCAL_BYTES: [[u32; 256]; 4] = pascal_bytes();

const fn pascal_bytes() -> [[u32; 256]; 4] {
    let mut columns = [0u32; 32];
    let mut v = 1u32 << 31;
    let mut j = 0;
    while j < 32 {
        columns[j] = v;
        v ^= v >> 1;
        j += 1;
    }
    let mut table = [[0u32; 256]; 4];
    let mut k = 0;
    while k < 4 {
        let mut x = 0;
        while x < 256 {
            let mut b = 0u32;
            let mut bit = 0;
            while bit < 8 {
                if (x >> bit) & 1 != 0 {
                    b ^= columns[8 * k + bit];
                }
                bit += 1;
            }
            table[k][x] = b;
            x += 1;
        }
        k += 1;
    }
    table
}

/// A permutation of `0..len` chosen by `p`, evaluated at `i` (Kensler 2013:
/// a hashed bijection on the next power of two, cycle-walked into range).
///
/// Where `len` is a power of two (the render's doubling spp) every step
/// lands in range and `p % len` is a mask: one step, no division. Elsewhere
/// the walk's first two steps are taken whatever their outcome and the
/// first one in range kept by a select: the loop's exit is a coin toss
/// there (at 72 samples a pixel, 43 % of steps land out of range), and its
/// mispredictions made the sampler twice as dear as at 64 (`perf`, 7.6 %
/// of a render against 3.7 %). Only a third step, rarer, branches. The
/// result is the walk's: the same permutation.
pub fn permute(i: u32, len: u32, p: u32) -> u32 {
    if len <= 1 {
        return 0;
    }
    let mut w = len - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    let first = kensler_step(i, w, p);
    if w == len - 1 {
        return first.wrapping_add(p) & w;
    }
    let second = kensler_step(first, w, p);
    let mut i = if first < len { first } else { second };
    while i >= len {
        i = kensler_step(i, w, p);
    }
    add_mod(i, p, len)
}

/// One step of Kensler's hashed bijection on `0..=w` (`w + 1` a power of two).
#[inline(always)]
fn kensler_step(mut i: u32, w: u32, p: u32) -> u32 {
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
    i
}

/// `(i + p) mod len` for `i < len`, with a 32-bit division (a 64-bit one
/// costs several times as much).
#[inline]
fn add_mod(i: u32, p: u32, len: u32) -> u32 {
    let shifted = u64::from(i) + u64::from(p % len);
    let len = u64::from(len);
    (if shifted >= len {
        shifted - len
    } else {
        shifted
    }) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Pascal matrix column by column, as the sequence defines it.
    fn sobol02_bit_by_bit(mut i: u32) -> (u32, u32) {
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

    #[test]
    fn the_byte_tables_give_the_sequence() {
        let spread = (0..4096u32).map(|k| k.wrapping_mul(0x9E37_79B9));
        for i in (0..70_000u32).chain(spread).chain([u32::MAX, 1 << 31]) {
            assert_eq!(sobol02(i), sobol02_bit_by_bit(i), "index {i}");
        }
    }

    #[test]
    fn add_mod_is_the_64_bit_remainder() {
        for len in [1u32, 2, 3, 96, 192, 1000, u32::MAX - 1, u32::MAX] {
            for p in [0u32, 1, 95, 0xDEAD_BEEF, u32::MAX] {
                for i in [0, 1, len / 2, len - 1] {
                    let expected = ((i as u64 + p as u64) % len as u64) as u32;
                    assert_eq!(add_mod(i, p, len), expected, "len {len} p {p} i {i}");
                }
            }
        }
    }

    /// The walk with its first steps taken unconditionally gives the plain
    /// walk's index, for every index of lengths on and off powers of two.
    #[test]
    fn the_walk_is_the_plain_cycle_walk() {
        let plain = |mut i: u32, len: u32, p: u32| {
            if len <= 1 {
                return 0;
            }
            let w = len.next_power_of_two() - 1;
            loop {
                i = kensler_step(i, w, p);
                if i < len {
                    break;
                }
            }
            add_mod(i, p, len)
        };
        for len in [2u32, 3, 4, 5, 17, 64, 72, 96, 128, 144, 1000, 4097, 1 << 16] {
            for p in [0u32, 1, 0xDEAD_BEEF, 0x9E37_79B9, u32::MAX] {
                for i in 0..len {
                    assert_eq!(
                        permute(i, len, p),
                        plain(i, len, p),
                        "len {len} p {p} i {i}"
                    );
                }
            }
        }
    }

    /// The first indices of a few permutations as an independent Python
    /// transcription of Kensler's listing gives them (arbitrary-precision
    /// integers masked to 32 bits): the walk is the published one.
    #[test]
    fn permutations_match_an_independent_transcription() {
        let cases: [(u32, u32, &[u32]); 4] = [
            (72, 0xDEAD_BEEF, &[43, 52, 10, 28, 9, 39, 34, 25]),
            (64, 12345, &[44, 55, 34, 35, 1, 39, 47, 23]),
            (144, 0x9E37_79B9, &[46, 9, 48, 110, 141, 11, 122, 30]),
            (3, 7, &[1, 2, 0]),
        ];
        for (len, p, want) in cases {
            let got: Vec<u32> = (0..want.len() as u32).map(|i| permute(i, len, p)).collect();
            assert_eq!(got, want, "len {len} p {p:#x}");
        }
    }

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
