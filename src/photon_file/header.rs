//! The 4096-byte header of a photon file (layout in `docs/photon-file.md`).

use crate::error::{Error, Result};
use crate::photon_map::Quantizer;
use glam::Vec3;

/// First 8 bytes of every photon file.
pub const MAGIC: [u8; 8] = *b"APMPHOT\0";
/// First 8 bytes of the trailer.
pub const TRAILER_MAGIC: [u8; 8] = *b"APMPEND\0";
/// Format version this build writes and reads.
pub const VERSION: u32 = 1;
/// Header bytes: one page, so the photons start page-aligned for `mmap`.
pub const HEADER_SIZE: usize = 4096;
/// Depths with their own count and power in the header (a compact photon stores depths 0..=63).
pub const DEPTHS: usize = 64;

/// Flag: the memory budget bound in at least one shard (the map then differs from an unbounded run's).
pub const FLAG_BUDGET_BOUND: u32 = 1;
/// Flag: the file is a merged map.
pub const FLAG_MERGED: u32 = 2;

/// The settings that decide a run's photons (a shard of another run never merges).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Settings {
    /// 0 classic, 1 density, 2 adaptive.
    pub mode: u8,
    /// 0 paper, 1 peak density.
    pub estimator: u8,
    /// Seed of every random number.
    pub seed: u64,
    /// `N_MAX`.
    pub n_max: u64,
    /// Bounce limit.
    pub max_depth: u32,
    /// Per-hit cap on children.
    pub split_cap: u32,
    /// Hash of the analysis constants ([`super::settings_hash`]).
    pub analysis_hash: u64,
}

/// Everything before the photons.
#[derive(Clone, Debug, PartialEq)]
pub struct Header {
    /// [`FLAG_BUDGET_BOUND`], [`FLAG_MERGED`].
    pub flags: u32,
    /// [`super::scene_hash`] of the scene traced.
    pub scene_hash: u64,
    /// The run's settings.
    pub settings: Settings,
    /// Shard index (0 for a merged map).
    pub shard_index: u32,
    /// Shard count (1 for a merged map).
    pub shard_count: u32,
    /// For a merged map, how many shards it was merged from; else 0.
    pub merged_from: u32,
    /// Photons in the file.
    pub photons: u64,
    /// Photons this shard emitted.
    pub emitted: u64,
    /// Photons the whole run emits.
    pub emitted_total: u64,
    /// Lower corner of the quantisation frame.
    pub frame_min: Vec3,
    /// Upper corner of the quantisation frame.
    pub frame_max: Vec3,
    /// Power scale of the frame (a power of two).
    pub power_scale: f32,
    /// [`super::MapHash`] sum of the photons.
    pub photon_sum: u64,
    /// The photons' map checksum ([`super::MapHash::checksum`]).
    pub map_checksum: u64,
    /// Photons whose power was above the scale (clamped).
    pub clamped: u64,
    /// Records skipped because they were not finite.
    pub skipped: u64,
    /// Photons stored at each depth (depths >= 63 are counted at 63).
    pub depth_photons: [u64; DEPTHS],
    /// RGB power stored at each depth (sums of the f32 powers, in f64).
    pub depth_power: [[f64; 3]; DEPTHS],
}

impl Header {
    /// The quantisation frame the photons are stored in.
    pub fn frame(&self) -> Quantizer {
        Quantizer::new(self.frame_min, self.frame_max, self.power_scale)
    }

    /// The header's 4096 bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(HEADER_SIZE);
        let s = &self.settings;
        b.extend_from_slice(&MAGIC);
        for v in [VERSION, HEADER_SIZE as u32, self.flags] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&[s.mode, s.estimator, 0, 0]);
        for v in [self.scene_hash, s.analysis_hash, s.seed, s.n_max] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        for v in [s.max_depth, s.split_cap, self.shard_index, self.shard_count] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        for v in [self.photons, self.emitted, self.emitted_total] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        for v in self
            .frame_min
            .to_array()
            .iter()
            .chain(&self.frame_max.to_array())
        {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&self.power_scale.to_le_bytes());
        b.extend_from_slice(&self.merged_from.to_le_bytes());
        for v in [
            self.photon_sum,
            self.map_checksum,
            self.clamped,
            self.skipped,
        ] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        debug_assert_eq!(b.len(), DEPTH_PHOTONS_AT);
        for v in self.depth_photons {
            b.extend_from_slice(&v.to_le_bytes());
        }
        for v in self.depth_power.iter().flatten() {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.resize(HEADER_SIZE, 0);
        b
    }

    /// Parses and checks a header (`bytes` holds at least [`HEADER_SIZE`] bytes).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] (`photon file`) for a wrong magic, an unknown
    /// version or a header size other than 4096.
    pub fn from_bytes(bytes: &[u8]) -> Result<Header> {
        let bad = |why: String| Error::param("photon file", why);
        if bytes.len() < HEADER_SIZE || bytes[..8] != MAGIC {
            return Err(bad("not an adaptive-pm photon file (bad magic)".into()));
        }
        let mut r = Cursor(&bytes[8..HEADER_SIZE]);
        let version = r.u32();
        if version != VERSION {
            return Err(bad(format!(
                "format version {version}, this build reads version {VERSION}"
            )));
        }
        let header_size = r.u32();
        if header_size as usize != HEADER_SIZE {
            return Err(bad(format!(
                "header size {header_size}, expected {HEADER_SIZE}"
            )));
        }
        let flags = r.u32();
        let (mode, estimator) = (r.u8(), r.u8());
        r.u16();
        let (scene_hash, analysis_hash, seed, n_max) = (r.u64(), r.u64(), r.u64(), r.u64());
        let (max_depth, split_cap, shard_index, shard_count) = (r.u32(), r.u32(), r.u32(), r.u32());
        let (photons, emitted, emitted_total) = (r.u64(), r.u64(), r.u64());
        let frame_min = Vec3::new(r.f32(), r.f32(), r.f32());
        let frame_max = Vec3::new(r.f32(), r.f32(), r.f32());
        let power_scale = r.f32();
        let merged_from = r.u32();
        let (photon_sum, map_checksum, clamped, skipped) = (r.u64(), r.u64(), r.u64(), r.u64());
        let depth_photons = std::array::from_fn(|_| r.u64());
        let depth_power = std::array::from_fn(|_| [r.f64(), r.f64(), r.f64()]);
        Ok(Header {
            flags,
            scene_hash,
            settings: Settings {
                mode,
                estimator,
                seed,
                n_max,
                max_depth,
                split_cap,
                analysis_hash,
            },
            shard_index,
            shard_count,
            merged_from,
            photons,
            emitted,
            emitted_total,
            frame_min,
            frame_max,
            power_scale,
            photon_sum,
            map_checksum,
            clamped,
            skipped,
            depth_photons,
            depth_power,
        })
    }
}

/// Offset of the per-depth photon counts (then the per-depth powers).
const DEPTH_PHOTONS_AT: usize = 160;

/// Little-endian reads from a slice known to be long enough (the header is
/// 4096 bytes; the fields take 2208).
struct Cursor<'a>(&'a [u8]);

impl Cursor<'_> {
    fn take<const N: usize>(&mut self) -> [u8; N] {
        let (head, rest) = self.0.split_at(N);
        self.0 = rest;
        let mut out = [0; N];
        out.copy_from_slice(head);
        out
    }
    fn u8(&mut self) -> u8 {
        self.take::<1>()[0]
    }
    fn u16(&mut self) -> u16 {
        u16::from_le_bytes(self.take())
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take())
    }
    fn u64(&mut self) -> u64 {
        u64::from_le_bytes(self.take())
    }
    fn f32(&mut self) -> f32 {
        f32::from_le_bytes(self.take())
    }
    fn f64(&mut self) -> f64 {
        f64::from_le_bytes(self.take())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_round_trips_in_4096_bytes() {
        let mut h = Header {
            flags: 3,
            scene_hash: 11,
            settings: Settings {
                mode: 2,
                estimator: 1,
                seed: 5,
                n_max: 100_000,
                max_depth: 15,
                split_cap: 4096,
                analysis_hash: 13,
            },
            shard_index: 2,
            shard_count: 7,
            merged_from: 0,
            photons: 123,
            emitted: 45,
            emitted_total: 300,
            frame_min: Vec3::new(-1.0, 0.0, 2.0),
            frame_max: Vec3::new(1.0, 3.0, 4.5),
            power_scale: 4096.0,
            photon_sum: 99,
            map_checksum: 77,
            clamped: 1,
            skipped: 2,
            depth_photons: [0; DEPTHS],
            depth_power: [[0.0; 3]; DEPTHS],
        };
        h.depth_photons[63] = 8;
        h.depth_power[63] = [1.5, 2.5, 3.5];
        let b = h.to_bytes();
        assert_eq!(b.len(), HEADER_SIZE);
        assert_eq!(Header::from_bytes(&b).unwrap(), h);
        let mut wrong = b.clone();
        wrong[8] = 9; // version
        assert!(Header::from_bytes(&wrong).is_err());
        assert!(Header::from_bytes(&b[..100]).is_err());
    }
}
