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
    /// Embree's kernel set that found the hits, as [`Isa::code`](crate::isa::Isa::code)
    /// (0: not recorded, the caster's hits do not depend on the CPU). Shards
    /// of different sets draw different photons, so they never merge.
    pub embree_isa: u8,
    /// Embree's version, [`Kernels::version_code`](crate::isa::Kernels::version_code) (0: not recorded).
    pub embree_version: u32,
    /// The tracing host's maths variant, [`MathVariant::code`](crate::isa::MathVariant::code) (0: not recorded).
    pub math_variant: u8,
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
        b.extend_from_slice(&[s.mode, s.estimator, s.embree_isa, s.math_variant]);
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
        b.extend_from_slice(&s.embree_version.to_le_bytes());
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
        let (mode, estimator, embree_isa, math_variant) = (r.u8(), r.u8(), r.u8(), r.u8());
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
        let embree_version = r.u32();
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
                embree_isa,
                embree_version,
                math_variant,
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

/// The largest power scale a photon file may declare: a photon carries at
/// most its light's power, which a scene bounds at
/// [`crate::scene::MAX_LIGHT_POWER`], times the quantiser's headroom
/// ([`crate::engine::POWER_HEADROOM`]). Above it the decoded powers, and
/// the sums a render makes of them, overflow f32: renders came out null or
/// zero.
pub const MAX_POWER_SCALE: f32 = crate::scene::MAX_LIGHT_POWER * crate::engine::POWER_HEADROOM;

/// Bounce limit a run may have (`TraceConfig::validate`).
const MAX_DEPTH_SETTING: u32 = 250;

impl Header {
    /// Checks every field against what a writer of this format can produce:
    /// known flags and modes, a shard index below a non-zero count (a merged
    /// map is shard 0 of 1), a finite frame with `min <= max`, a finite power
    /// scale in `0..=`[`MAX_POWER_SCALE`], per-depth counts that add up to the
    /// photon count, finite non-negative per-depth powers, and a map checksum
    /// that matches the photon count, sum and frame. Nothing else in the
    /// crate trusts a header field that this does not check.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] (`photon file`) naming the field and value.
    pub fn validate(&self) -> Result<()> {
        self.problem()
            .map_or(Ok(()), |why| Err(Error::param("photon file", why)))
    }

    /// What is wrong with the header, if anything (see [`Header::validate`]).
    fn problem(&self) -> Option<String> {
        let known = FLAG_BUDGET_BOUND | FLAG_MERGED;
        if self.flags & !known != 0 {
            return Some(format!("unknown flags {:#x}", self.flags & !known));
        }
        let s = &self.settings;
        if s.mode > 2 || s.estimator > 2 {
            return Some(format!(
                "unknown mode {} or estimator {}",
                s.mode, s.estimator
            ));
        }
        if s.embree_isa != 0 && crate::isa::Isa::from_code(s.embree_isa).is_none() {
            return Some(format!("unknown Embree kernel set code {}", s.embree_isa));
        }
        if s.math_variant != 0 && crate::isa::MathVariant::from_code(s.math_variant).is_none() {
            return Some(format!("unknown maths variant code {}", s.math_variant));
        }
        if s.max_depth > MAX_DEPTH_SETTING || s.split_cap == 0 {
            return Some(format!(
                "max depth {} (at most {MAX_DEPTH_SETTING}) or split cap {} (at least 1) out of range",
                s.max_depth, s.split_cap
            ));
        }
        if let Some(why) = self.shard_problem() {
            return Some(why);
        }
        if self.emitted > self.emitted_total {
            return Some(format!(
                "emitted {} is above the run's total {}",
                self.emitted, self.emitted_total
            ));
        }
        if let Some(why) = self.frame_problem() {
            return Some(why);
        }
        self.count_problem()
    }

    fn shard_problem(&self) -> Option<String> {
        let (i, n) = (self.shard_index, self.shard_count);
        if n == 0 || i >= n {
            return Some(format!(
                "shard {i}/{n}: the index must be below a non-zero count"
            ));
        }
        let merged = self.flags & FLAG_MERGED != 0;
        if merged && (n != 1 || self.merged_from == 0) {
            return Some(format!(
                "a merged map must be shard 0/1 of at least one shard, got {i}/{n} from {}",
                self.merged_from
            ));
        }
        if !merged && self.merged_from != 0 {
            return Some(format!(
                "an unmerged shard says it was merged from {} shards",
                self.merged_from
            ));
        }
        None
    }

    fn frame_problem(&self) -> Option<String> {
        let (lo, hi) = (self.frame_min, self.frame_max);
        if !lo.is_finite() || !hi.is_finite() || !lo.cmple(hi).all() {
            return Some(format!(
                "frame bounds {lo} .. {hi} are not finite or inverted"
            ));
        }
        let p = self.power_scale;
        // `contains` is false for NaN.
        if !(0.0..=MAX_POWER_SCALE).contains(&p) || (p == 0.0 && self.photons > 0) {
            return Some(format!(
                "power scale {p:e} is not in (0, {MAX_POWER_SCALE:e}]"
            ));
        }
        None
    }

    fn count_problem(&self) -> Option<String> {
        if self.clamped > self.photons {
            return Some(format!(
                "{} clamped photons but {} photons",
                self.clamped, self.photons
            ));
        }
        let counted = self
            .depth_photons
            .iter()
            .try_fold(0u64, |a, &n| a.checked_add(n));
        if counted != Some(self.photons) {
            return Some(format!(
                "the per-depth counts do not add up to its {} photons",
                self.photons
            ));
        }
        if let Some(d) = self
            .depth_power
            .iter()
            .position(|c| c.iter().any(|p| !p.is_finite() || *p < 0.0))
        {
            return Some(format!(
                "the power at depth {d}, {:?}, is not finite and non-negative",
                self.depth_power[d]
            ));
        }
        let announced = super::MapHash {
            count: self.photons,
            sum: self.photon_sum,
        };
        if announced.checksum(&self.frame()) != self.map_checksum {
            return Some(
                "its map checksum does not match its photon count, sum and frame (corrupt)".into(),
            );
        }
        None
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
                embree_isa: 4,
                embree_version: 31305,
                math_variant: 3,
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

    /// A header as a writer makes it: consistent counts and checksum.
    fn consistent() -> Header {
        let mut h = Header {
            flags: 0,
            scene_hash: 1,
            settings: Settings {
                mode: 2,
                estimator: 0,
                seed: 1,
                n_max: 1000,
                max_depth: 15,
                split_cap: 4096,
                analysis_hash: 2,
                embree_isa: 0,
                embree_version: 0,
                math_variant: 0,
            },
            shard_index: 1,
            shard_count: 2,
            merged_from: 0,
            photons: 10,
            emitted: 500,
            emitted_total: 1000,
            frame_min: Vec3::ZERO,
            frame_max: Vec3::ONE,
            power_scale: 64.0,
            photon_sum: 1234,
            map_checksum: 0,
            clamped: 0,
            skipped: 0,
            depth_photons: [0; DEPTHS],
            depth_power: [[0.0; 3]; DEPTHS],
        };
        h.depth_photons[0] = 6;
        h.depth_photons[1] = 4;
        h.depth_power[0] = [1.0, 2.0, 3.0];
        h.map_checksum = reseal(&h);
        h
    }

    fn reseal(h: &Header) -> u64 {
        super::super::MapHash {
            count: h.photons,
            sum: h.photon_sum,
        }
        .checksum(&h.frame())
    }

    #[test]
    fn validate_refuses_every_field_out_of_range() {
        consistent().validate().unwrap();
        type Mutation = fn(&mut Header);
        let cases: [(Mutation, &str); 14] = [
            (|h| h.flags = 8, "unknown flags"),
            (|h| h.settings.mode = 3, "unknown mode"),
            (|h| h.settings.split_cap = 0, "split cap"),
            (|h| h.shard_count = 0, "shard 1/0"),
            (|h| h.shard_index = 2, "shard 2/2"),
            (|h| h.merged_from = 2, "unmerged shard"),
            (|h| h.flags = FLAG_MERGED, "merged map"),
            (|h| h.emitted = 1001, "above the run's total"),
            (|h| h.frame_min.x = f32::NAN, "frame bounds"),
            (|h| h.frame_max.y = -1.0, "frame bounds"),
            (|h| h.power_scale = f32::INFINITY, "power scale"),
            (|h| h.power_scale = 3.4e38, "power scale"),
            (|h| h.depth_photons[63] = u64::MAX, "per-depth counts"),
            (|h| h.depth_power[5][1] = f64::NAN, "depth 5"),
        ];
        for (mutate, expect) in cases {
            let mut h = consistent();
            mutate(&mut h);
            // Resealed: the checks do not lean on the checksum alone.
            h.map_checksum = reseal(&h);
            let e = h.validate().unwrap_err().to_string();
            assert!(e.contains(expect), "expected `{expect}` in `{e}`");
        }
        let mut h = consistent();
        h.photon_sum ^= 1;
        let e = h.validate().unwrap_err().to_string();
        assert!(e.contains("map checksum"), "{e}");
    }
}
