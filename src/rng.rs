//! Counter-based random numbers: a stream per photon, derived from the photon's
//! identity (seed, light, index, child number), never from the thread that runs it.
//! That is what makes a photon map bitwise identical whatever the thread count.

/// SplitMix64's finaliser: a bijective 64-bit mixer.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Combines two keys into one (order matters).
#[inline]
pub fn hash2(a: u64, b: u64) -> u64 {
    mix64(a ^ mix64(b).rotate_left(17))
}

/// PCG32 (XSH-RR), small and statistically sound for Monte Carlo.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
    inc: u64,
}

impl Rng {
    /// A generator whose whole sequence is fixed by `key` (for instance
    /// `hash2(seed, photon_id)`).
    pub fn new(key: u64) -> Self {
        // Both words hashed from the key: nearby keys (photon i and i + 1)
        // start on unrelated states and streams.
        let mut rng = Rng {
            state: mix64(key),
            inc: (mix64(key ^ 0xDA3E_39CB_94B9_5BDB) << 1) | 1,
        };
        rng.next_u32();
        rng
    }

    /// Next 32 random bits.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1), never 1.
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Uniform in [0, 1), 53 bits.
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        let hi = (self.next_u32() as u64) << 21;
        let lo = (self.next_u32() >> 11) as u64;
        (hi | lo) as f64 * (1.0 / 9_007_199_254_740_992.0)
    }

    /// Two uniforms in [0, 1), the argument every sampler takes.
    #[inline]
    pub fn next_2d(&mut self) -> [f32; 2] {
        [self.next_f32(), self.next_f32()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_key_same_sequence_and_keys_differ() {
        let a: Vec<u32> = (0..8)
            .map({
                let mut r = Rng::new(42);
                move |_| r.next_u32()
            })
            .collect();
        let b: Vec<u32> = (0..8)
            .map({
                let mut r = Rng::new(42);
                move |_| r.next_u32()
            })
            .collect();
        let c: Vec<u32> = (0..8)
            .map({
                let mut r = Rng::new(43);
                move |_| r.next_u32()
            })
            .collect();
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn uniform_mean_and_range() {
        // A fixed seed: the generator is pure integer arithmetic, the same
        // draw on every machine. The bound is nevertheless statistical: 5
        // standard errors of the mean, measured from the draws' own variance
        // (U(0,1): 1/sqrt(12 n) ~ 6.5e-4).
        let mut r = Rng::new(7);
        let n = 200_000;
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let x = r.next_f32();
            assert!((0.0..1.0).contains(&x));
            sum += x as f64;
            sum2 += x as f64 * x as f64;
        }
        let mean = sum / n as f64;
        let var = (sum2 - n as f64 * mean * mean) / (n - 1) as f64;
        let se = (var / n as f64).sqrt();
        // The variance of U(0,1), 1/12, within 5 of its standard errors
        // (relative sqrt((kurtosis - 1) / n) = sqrt(0.8 / n) = 0.2 %).
        assert!((var * 12.0 - 1.0).abs() < 0.01, "variance {var}");
        assert!((mean - 0.5).abs() < 5.0 * se, "{mean} +- {se}");
    }
}
