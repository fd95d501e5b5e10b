//! The photons the kd-tree comparisons with kiddo build and query, shared by
//! `benches/kdtree.rs` and `benches/kdtree_vs_kiddo.rs` so that both measure
//! the same maps.

use adaptive_pm::photon_map::{CompactPhoton, PhotonRecord, Quantizer};
use adaptive_pm::rng::Rng;
use glam::Vec3;

/// `n` photons uniform in the unit cube, with random powers, directions and
/// depths, from `seed`.
pub fn records(n: usize, seed: u64) -> Vec<PhotonRecord> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| PhotonRecord {
            position: Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()),
            power: Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()),
            direction: Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5,
            depth: (rng.next_u32() % 4) as u8,
            caustic: false,
        })
        .collect()
}

/// The records' positions, as kiddo takes them.
pub fn points(records: &[PhotonRecord]) -> Vec<[f32; 3]> {
    records.iter().map(|r| r.position.to_array()).collect()
}

/// The frame the records are encoded in: the unit cube.
pub fn unit_frame() -> Quantizer {
    Quantizer::new(Vec3::ZERO, Vec3::ONE, 1.0)
}

/// The records encoded as the tracer writes them, in [`unit_frame`].
pub fn compact(records: &[PhotonRecord]) -> (Vec<CompactPhoton>, Quantizer) {
    let q = unit_frame();
    (records.iter().map(|r| q.encode(r)).collect(), q)
}
