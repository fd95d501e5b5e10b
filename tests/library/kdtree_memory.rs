//! Peak memory of building a 10M-photon map against its photon bytes (goal: at most
//! 1.5x). Not run in CI (`#[ignore]`, needs ~1 GB and a release build):
//! `cargo test --release --test kdtree_memory -- --ignored --nocapture`.

use adaptive_pm::photon_map::{PhotonMap, PhotonRecord};
use adaptive_pm::rng::Rng;
use glam::Vec3;

/// The process's peak resident memory (VmHWM), in bytes.
fn peak_rss() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        .map_or(0, |kb| kb * 1024)
}

#[test]
#[ignore]
fn build_peak_memory_is_close_to_the_photon_bytes() {
    let n = 10_000_000;
    let mut rng = Rng::new(5);
    let records: Vec<PhotonRecord> = (0..n)
        .map(|_| PhotonRecord {
            position: Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()),
            power: Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()),
            direction: Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5,
            depth: 0,
            caustic: false,
        })
        .collect();
    let before = peak_rss();
    let t = std::time::Instant::now();
    let map = PhotonMap::build(&records);
    let elapsed = t.elapsed();
    let after = peak_rss();
    let photon_bytes = (map.len() * map.bytes_per_photon()) as u64;
    let ratio = (after - before) as f64 / photon_bytes as f64;
    println!(
        "10M photons: built in {elapsed:?}; VmHWM {} MB -> {} MB; photon bytes {} MB; \
         map memory {} MB; build peak / photon bytes = {ratio:.3}",
        before >> 20,
        after >> 20,
        photon_bytes >> 20,
        map.memory_bytes() >> 20
    );
    assert!(before > 0, "no /proc/self/status");
    assert!(ratio <= 1.5, "peak {ratio:.2}x the photon bytes");
}
