//! Which stored photons a render reads (issue 27): of the photons the
//! renderer keeps, the share that at least one k-nearest lookup of the
//! render returns (a pixel's first-hit estimate, a gather ray's estimate,
//! the irradiance cache's build estimates). A photon that no lookup
//! returns costs memory and trace time and changes no pixel.
//!
//! The cache's build lookups are marked apart
//! ([`MapReads::share_without_cache_build`]): the cache estimates a cell
//! wherever a photon sample lies, seen or not, so they read most of any map.
//!
//! Opt-in ([`super::render_reading`]): a plain render carries no marks and
//! pays one untaken branch per lookup. With marks, each image row keeps a
//! bitset per map (`RowReads`) and each of the cache build's rayon tasks
//! one of its own (`BuildReads`), OR-ed into the shared ones when done:
//! no atomics in the hot loops (shared bits set per photon cost the study's
//! renders 20-37 % more time, neighbours sharing cache lines across
//! threads). A union does not depend on the order of its parts, so the
//! marks are the same whatever the thread count.
//!
//! The maps hold copies of the same records (the full map all of them, the
//! primary, indirect and caustic maps subsets), so a photon is identified by
//! its record ([`PhotonMap::record_indices`]): the share is over the
//! records, a record read when any map's copy of it was returned.

use super::RenderMaps;
use crate::error::{Error, Result};
use crate::photon_map::{Neighbor, PhotonMap, PhotonRecord};
use std::sync::atomic::{AtomicU64, Ordering};

/// The maps of [`RenderMaps`], in the order of [`MapReads`]'s bitsets.
const MAPS: usize = 4;

/// The records each map of [`RenderMaps::build`] keeps, in [`MAPS`] order.
const FILTERS: [fn(&PhotonRecord) -> bool; MAPS] = [
    |_| true,
    |r| r.depth == 0,
    |r| r.depth >= 1 && !r.caustic,
    |r| r.caustic,
];

/// The marks of one render over `maps`: for each map, a bit per photon
/// (tree order) set when a pixel's or a gather ray's lookup returned it,
/// and for the full map a bit set when the cache's build did.
pub struct MapReads<'a> {
    maps: &'a RenderMaps,
    bits: [Vec<AtomicU64>; MAPS],
    cache_build: Vec<AtomicU64>,
}

impl std::fmt::Debug for MapReads<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MapReads")
            .field("read_counts", &self.read_counts())
            .finish()
    }
}

impl<'a> MapReads<'a> {
    /// No photon read yet.
    pub fn new(maps: &'a RenderMaps) -> Self {
        let words = |m: &PhotonMap| {
            (0..m.len().div_ceil(64))
                .map(|_| AtomicU64::new(0))
                .collect()
        };
        MapReads {
            maps,
            cache_build: words(&maps.full),
            bits: [
                words(&maps.full),
                words(&maps.primary),
                words(&maps.indirect),
                words(&maps.caustic),
            ],
        }
    }

    /// The maps these marks are of.
    pub fn maps(&self) -> &'a RenderMaps {
        self.maps
    }

    fn all(&self) -> [&PhotonMap; MAPS] {
        let m = self.maps;
        [&m.full, &m.primary, &m.indirect, &m.caustic]
    }

    /// Which of the maps `map` is (by address: the render reads them in place).
    fn which(&self, map: &PhotonMap) -> Option<usize> {
        self.all().iter().position(|m| std::ptr::eq(*m, map))
    }

    /// ORs a finished row's marks in.
    pub(crate) fn merge(&self, row: &RowReads) {
        for (shared, words) in self.bits.iter().zip(&row.words) {
            for (s, &w) in shared.iter().zip(words) {
                if w != 0 {
                    s.fetch_or(w, Ordering::Relaxed);
                }
            }
        }
    }

    /// Photons of each map (full, primary, indirect, caustic) that a
    /// pixel's or a gather ray's lookup read so far, and of the full map
    /// that the cache's build read.
    pub fn read_counts(&self) -> ([usize; MAPS], usize) {
        let count = |b: &Vec<AtomicU64>| {
            b.iter()
                .map(|w| w.load(Ordering::Relaxed).count_ones() as usize)
                .sum()
        };
        (self.bits.each_ref().map(count), count(&self.cache_build))
    }

    /// The share of the stored records that some lookup read, the cache's
    /// build included: records read through any map over the full map's
    /// photons (every valid record); 0 for an empty map.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] when the maps were not built by
    /// [`RenderMaps::build`] from `records`.
    pub fn share(&self, records: &[PhotonRecord]) -> Result<f64> {
        self.share_of(records, true)
    }

    /// [`MapReads::share`] without the cache's build lookups: the photons
    /// that pixels and gather rays read themselves.
    ///
    /// # Errors
    /// As [`MapReads::share`].
    pub fn share_without_cache_build(&self, records: &[PhotonRecord]) -> Result<f64> {
        self.share_of(records, false)
    }

    fn share_of(&self, records: &[PhotonRecord], with_build: bool) -> Result<f64> {
        let total = self.maps.full.len();
        if total == 0 {
            return Ok(0.0);
        }
        let mut read = vec![false; records.len()];
        let maps = self.all().into_iter().zip(&self.bits).zip(FILTERS);
        let build = with_build.then_some(((&self.maps.full, &self.cache_build), FILTERS[0]));
        for ((map, bits), keep) in maps.chain(build) {
            if map.is_empty() {
                continue;
            }
            let owners = map.record_indices(records, keep).ok_or_else(|| {
                Error::param(
                    "read share",
                    "the maps were not built by RenderMaps::build from these records",
                )
            })?;
            for (slot, &owner) in owners.iter().enumerate() {
                if bits[slot / 64].load(Ordering::Relaxed) >> (slot % 64) & 1 == 1 {
                    read[owner as usize] = true;
                }
            }
        }
        Ok(read.iter().filter(|&&r| r).count() as f64 / total as f64)
    }
}

/// One image row's marks: plain words, sized on a map's first mark.
#[derive(Default)]
pub(crate) struct RowReads {
    words: [Vec<u64>; MAPS],
}

impl RowReads {
    /// Marks the photons of `found`, returned by a lookup in `map`.
    pub(crate) fn mark(&mut self, reads: &MapReads, map: &PhotonMap, found: &[Neighbor]) {
        let Some(w) = reads.which(map) else {
            return;
        };
        let words = &mut self.words[w];
        if words.is_empty() {
            words.resize(map.len().div_ceil(64), 0);
        }
        for n in found {
            let i = n.index as usize;
            words[i / 64] |= 1 << (i % 64);
        }
    }
}

/// One cache-build task's marks of the full map, OR-ed into the shared ones
/// when dropped (at the end of the task).
pub(crate) struct BuildReads<'r, 'a> {
    reads: &'r MapReads<'a>,
    words: Vec<u64>,
}

impl<'r, 'a> BuildReads<'r, 'a> {
    pub(crate) fn new(reads: &'r MapReads<'a>) -> Self {
        BuildReads {
            reads,
            words: Vec::new(),
        }
    }

    /// Marks the photons of `found`, returned by a build lookup in `map`
    /// (the full map; another map is not the cache's).
    pub(crate) fn mark(&mut self, map: &PhotonMap, found: &[Neighbor]) {
        if self.reads.which(map) != Some(0) {
            return;
        }
        if self.words.is_empty() {
            self.words.resize(map.len().div_ceil(64), 0);
        }
        for n in found {
            let i = n.index as usize;
            self.words[i / 64] |= 1 << (i % 64);
        }
    }
}

impl Drop for BuildReads<'_, '_> {
    fn drop(&mut self) {
        for (s, &w) in self.reads.cache_build.iter().zip(&self.words) {
            if w != 0 {
                s.fetch_or(w, Ordering::Relaxed);
            }
        }
    }
}
