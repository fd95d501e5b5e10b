//! Which record each photon of a map was built from: the map stores photons
//! in tree order, without their record's index, so an experiment that marks
//! the photons a lookup returns ([`crate::render::reads`]) finds their
//! records again here, without a field in the map that every render would
//! pay for.
//!
//! The tree holds exactly the encoded records that passed the filter (its
//! array depends only on their multiset, [`super::kdtree`]), so sorting both
//! by their 16 bytes (split axis cleared) pairs every photon with a record
//! that encodes to the same bytes. Records that encode alike are paired in
//! index order: which of two identical photons is which does not matter.

use super::kdtree::{is_valid, PhotonMap};
use super::photon::CompactPhoton;
use super::PhotonRecord;
use rayon::prelude::*;

/// A photon's bytes without its split axis (set by the build, not the record).
fn key(c: &CompactPhoton) -> (u64, u64) {
    let mut c = *c;
    c.set_axis(0);
    c.bits()
}

impl PhotonMap {
    /// For each photon of the map, in tree order, the index in `records` of
    /// the record it was encoded from, when the map is
    /// `PhotonMap::build_filtered(records, keep)`; `None` when it is not
    /// (the filtered records do not encode to the map's photons).
    pub fn record_indices<F>(&self, records: &[PhotonRecord], keep: F) -> Option<Vec<u32>>
    where
        F: Fn(&PhotonRecord) -> bool + Sync,
    {
        let mut encoded: Vec<((u64, u64), u32)> = records
            .par_iter()
            .enumerate()
            .filter(|(_, r)| is_valid(r) && keep(r))
            .map(|(i, r)| (key(&self.quant.encode(r)), i as u32))
            .collect();
        if encoded.len() != self.photons.len() {
            return None;
        }
        let mut slots: Vec<((u64, u64), u32)> = self
            .photons
            .par_iter()
            .enumerate()
            .map(|(i, c)| (key(c), i as u32))
            .collect();
        encoded.par_sort_unstable();
        slots.par_sort_unstable();
        let mut owners = vec![0u32; slots.len()];
        for ((record_key, record), (slot_key, slot)) in encoded.iter().zip(&slots) {
            if record_key != slot_key {
                return None;
            }
            owners[*slot as usize] = *record;
        }
        Some(owners)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use glam::Vec3;

    fn records(n: usize, seed: u64) -> Vec<PhotonRecord> {
        let mut rng = Rng::new(seed);
        (0..n)
            .map(|i| PhotonRecord {
                // A coarse lattice: many photons encode alike.
                position: Vec3::new((rng.next_f32() * 4.0).floor(), rng.next_f32(), 0.0),
                power: Vec3::splat(1.0 + (i % 3) as f32),
                direction: -Vec3::Y,
                depth: (i % 3) as u8,
                caustic: false,
            })
            .collect()
    }

    #[test]
    fn every_photon_finds_a_record_that_encodes_to_it_once() {
        let recs = records(3000, 3);
        let keep = |r: &PhotonRecord| r.depth >= 1;
        let map = PhotonMap::build_filtered(&recs, keep);
        let owners = map.record_indices(&recs, keep).unwrap();
        let mut seen = vec![false; recs.len()];
        for (slot, &r) in owners.iter().enumerate() {
            assert!(keep(&recs[r as usize]));
            assert!(
                !std::mem::replace(&mut seen[r as usize], true),
                "record {r} twice"
            );
            assert_eq!(
                key(&map.quant.encode(&recs[r as usize])),
                key(map.compact(slot as u32))
            );
        }
        // Records the map was not built from are refused.
        assert!(map.record_indices(&recs, |_| true).is_none());
        assert!(map.record_indices(&records(3000, 4), keep).is_none());
    }
}
