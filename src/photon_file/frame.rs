//! The run's canonical quantisation frame, the hashes of a scene and of its
//! settings, the order-independent map checksum and the file checksum.

use crate::engine::buffer::frame_inputs;
use crate::engine::counts::LightPlan;
use crate::engine::TraceConfig;
use crate::photon_map::{CompactPhoton, Quantizer};
use crate::rng::{hash2, mix64};
use crate::scene::Scene;

/// The frame every shard of a run quantises in (the tracer writes its
/// photons in it): the scene's bounding box and a power scale
/// `engine::buffer::POWER_HEADROOM` times the brightest emitted photon's largest channel.
/// Both depend only on the scene and the emission plan, so every shard
/// computes the same frame.
pub fn canonical_frame(scene: &Scene, plans: &[LightPlan]) -> CanonicalFrame {
    let (min, max, power_scale) = frame_inputs(scene, plans);
    CanonicalFrame {
        min,
        max,
        power_scale,
    }
}

/// The inputs of a run's quantisation frame, as a photon file stores them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CanonicalFrame {
    /// Lower corner of the scene's bounds.
    pub min: glam::Vec3,
    /// Upper corner.
    pub max: glam::Vec3,
    /// Power scale, a power of two.
    pub power_scale: f32,
}

impl CanonicalFrame {
    /// Whether `q` is this frame's quantiser (bit for bit).
    pub fn matches(&self, q: &Quantizer) -> bool {
        self.quantizer().bits() == q.bits()
    }

    /// The quantiser of this frame.
    pub fn quantizer(&self) -> Quantizer {
        Quantizer::new(self.min, self.max, self.power_scale)
    }
}

/// A streaming hash of 8-byte little-endian words (the file checksum).
#[derive(Clone, Copy, Debug)]
pub struct ByteHash(u64);

impl Default for ByteHash {
    fn default() -> Self {
        ByteHash(mix64(0xA9E0_F11E))
    }
}

impl ByteHash {
    /// Adds `bytes`; its length must be a multiple of 8 (every part of the file is).
    pub fn update(&mut self, bytes: &[u8]) {
        debug_assert_eq!(bytes.len() % 8, 0);
        for w in bytes.chunks_exact(8) {
            let word = u64::from_le_bytes([w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7]]);
            self.0 = hash2(self.0, word);
        }
    }

    /// The hash so far.
    pub fn value(&self) -> u64 {
        self.0
    }
}

/// The order-independent checksum of a photon map: a hash of its frame, its
/// photon count and the wrapping sum of one hash per photon. Equal multisets
/// of compact photons in equal frames give equal checksums, in any order:
/// a merged map reproduces the whole run's checksum whatever the order of
/// its shards.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MapHash {
    /// Photons added.
    pub count: u64,
    /// Wrapping sum of the photons' hashes.
    pub sum: u64,
}

impl MapHash {
    /// Adds one photon (its split-axis bits are ignored).
    #[inline]
    pub fn add(&mut self, p: &CompactPhoton) {
        let (a, b) = CompactPhoton::from_bits(p.bits().0, p.bits().1).bits();
        self.count += 1;
        self.sum = self.sum.wrapping_add(hash2(hash2(0x9407_0A5E, a), b));
    }

    /// Adds another map's photons.
    pub fn combine(&mut self, other: &MapHash) {
        self.count += other.count;
        self.sum = self.sum.wrapping_add(other.sum);
    }

    /// The checksum of these photons in `frame`.
    pub fn checksum(&self, frame: &Quantizer) -> u64 {
        let h = frame.bits().iter().fold(mix64(1), |h, &b| hash2(h, b));
        hash2(hash2(h, self.count), self.sum)
    }
}

/// The checksum `trace --json` prints: the run's compact photons (in any
/// order: the hash is a sum) in its canonical frame, hashed with [`MapHash`].
pub fn photons_checksum(photons: &[CompactPhoton], frame: &Quantizer) -> u64 {
    use rayon::prelude::*;
    let h = photons
        .par_iter()
        .with_min_len(4096)
        .fold(MapHash::default, |mut h, p| {
            h.add(p);
            h
        })
        .reduce(MapHash::default, |mut a, b| {
            a.combine(&b);
            a
        });
    h.checksum(frame)
}

/// A `fmt::Write` that hashes what is written, so a value's `Debug` text is
/// hashed without being held in memory.
struct HashWriter(u64, [u8; 8], usize);

impl std::fmt::Write for HashWriter {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        for &b in s.as_bytes() {
            self.1[self.2] = b;
            self.2 += 1;
            if self.2 == 8 {
                self.0 = hash2(self.0, u64::from_le_bytes(self.1));
                self.2 = 0;
            }
        }
        Ok(())
    }
}

fn debug_hash(seed: u64, value: &dyn std::fmt::Debug) -> u64 {
    use std::fmt::Write;
    let mut w = HashWriter(mix64(seed), [0; 8], 0);
    // Writing to a hasher cannot fail.
    let _ = write!(w, "{value:?}");
    let tail = u64::from_le_bytes(w.1) ^ ((w.2 as u64) << 56);
    hash2(w.0, tail)
}

/// A hash of everything the scene holds (geometry, materials, lights, camera,
/// after any `--cosn` override): shards of different scenes never merge.
/// Hashed through the scene's `Debug` text, which prints every f32 exactly
/// (shortest round-trip form), so equal scenes hash equal in one build.
pub fn scene_hash(scene: &Scene) -> u64 {
    debug_hash(0x5CE4E, scene)
}

/// A hash of the settings that change the photons but have no field of their
/// own in the header: the directionality analysis's constants, and the
/// importance pass when there is one.
pub fn settings_hash(cfg: &TraceConfig) -> u64 {
    match &cfg.importance {
        None => debug_hash(0x5E771, &cfg.analysis),
        // Importance changes every count: shards with other passes (or
        // none) never merge. Without it, the hash is what it always was.
        Some(imp) => debug_hash(0x5E771, &(&cfg.analysis, imp)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn map_hash_is_order_independent_and_counts() {
        let q = Quantizer::new(glam::Vec3::ZERO, glam::Vec3::ONE, 1.0);
        let ps: Vec<CompactPhoton> = (0..10)
            .map(|i| {
                q.encode(&crate::photon_map::PhotonRecord {
                    position: glam::Vec3::splat(i as f32 / 10.0),
                    power: glam::Vec3::ONE,
                    direction: glam::Vec3::Z,
                    depth: 0,
                    caustic: false,
                })
            })
            .collect();
        let mut a = MapHash::default();
        ps.iter().for_each(|p| a.add(p));
        let mut b = MapHash::default();
        ps.iter().rev().for_each(|p| b.add(p));
        assert_eq!(a.checksum(&q), b.checksum(&q));
        let mut c = MapHash::default();
        ps[1..].iter().for_each(|p| c.add(p));
        assert_ne!(a.checksum(&q), c.checksum(&q));
    }
}
