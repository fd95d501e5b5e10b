//! Why the irradiance cache counts only the photons that are not samples
//! (README, "Bias against the photon count"): on a uniform density, the
//! cone-filtered k-nearest estimate (k = 100) evaluated
//! - at random points reads the density (unbiased);
//! - at photons of the map, that photon counted, reads `(k + 1) / (k - 2)`;
//! - at photons, that photon left out, reads the density again (Slivnyak);
//! - at one sample kept per cell (samples: one photon in 8 by a coin), the
//!   other samples counted, reads low: a cell exists because it holds
//!   samples, so per cell fewer of them lie near its point;
//! - the same with only the non-samples counted (times 8/7): unbiased.
//!
//! `cargo run --release --example kernel_at_photons` prints each over the
//! exact density.

use adaptive_pm::photon_map::{Neighbor, PhotonMap, PhotonRecord};
use adaptive_pm::rng::Rng;
use glam::Vec3;
use std::collections::HashMap;

const K: usize = 100;
const STRIDE: u64 = 8;

fn main() {
    let n = 200_000usize;
    let mut rng = Rng::new(12345);
    let records: Vec<PhotonRecord> = (0..n)
        .map(|_| PhotonRecord {
            position: Vec3::new(rng.next_f32(), 0.0, rng.next_f32()),
            power: Vec3::ONE,
            direction: -Vec3::Y,
            depth: 0,
            caustic: false,
        })
        .collect();
    let map = PhotonMap::build(&records);
    let mut scratch: Vec<Neighbor> = Vec::new();
    // The cone estimate of the photon count per unit area, over the photons
    // `keep` accepts, times `scale`.
    let mut estimate = |x: Vec3, keep: &dyn Fn(u32) -> bool, scale: f64| {
        // A photon's index in the map, from its address in the map's array.
        let base = map.compact_photons().as_ptr() as usize;
        let size = std::mem::size_of_val(&map.compact_photons()[0]);
        map.nearest_k_where(x, K, f32::INFINITY, &mut scratch, |c| {
            keep(((c as *const _ as usize - base) / size) as u32)
        });
        let r2 = scratch[scratch.len() - 1].dist2;
        let r = r2.sqrt();
        let sum: f32 = scratch
            .iter()
            .map(|nb| (1.0 - nb.dist2.sqrt() / r).max(0.0))
            .sum();
        sum as f64 * 3.0 / (std::f64::consts::PI * r2 as f64) * scale
    };
    let exact = n as f64;
    let inner = |p: Vec3| p.x > 0.2 && p.x < 0.8 && p.z > 0.2 && p.z < 0.8;
    let coin = |i: u32| map.compact(i).content_hash() % STRIDE == 0;
    let m = 20_000;

    let mut random = 0.0;
    for _ in 0..m {
        let x = Vec3::new(0.2 + 0.6 * rng.next_f32(), 0.0, 0.2 + 0.6 * rng.next_f32());
        random += estimate(x, &|_| true, 1.0);
    }
    let (mut with_own, mut without_own, mut count) = (0.0, 0.0, 0);
    for i in (0..map.len() as u32).step_by(7) {
        let p = map.photon(i).position;
        if inner(p) && count < m {
            with_own += estimate(p, &|_| true, 1.0);
            without_own += estimate(p, &|j| j != i, 1.0);
            count += 1;
        }
    }
    // One sample per cell (side 0.011, ~3 samples each), the least coin.
    let h = 0.011f32;
    let mut cells: HashMap<(i32, i32), (u64, u32)> = HashMap::new();
    for i in 0..map.len() as u32 {
        let p = map.photon(i).position;
        let hash = map.compact(i).content_hash();
        if hash % STRIDE == 0 && inner(p) {
            let key = ((p.x / h).floor() as i32, (p.z / h).floor() as i32);
            let e = cells.entry(key).or_insert((u64::MAX, 0));
            if hash < e.0 {
                *e = (hash, i);
            }
        }
    }
    let (mut other_samples, mut non_samples) = (0.0, 0.0);
    for &(_, i) in cells.values() {
        let p = map.photon(i).position;
        other_samples += estimate(p, &|j| j != i, 1.0);
        non_samples += estimate(p, &|j| !coin(j), STRIDE as f64 / (STRIDE - 1) as f64);
    }
    let c = cells.len() as f64;
    println!("estimate / exact density, k = {K}, {n} photons on a unit square:");
    println!(
        "  random points                       {:.4}",
        random / m as f64 / exact
    );
    println!(
        "  at photons, own photon counted      {:.4}  (k+1)/(k-2) = {:.4}",
        with_own / count as f64 / exact,
        (K + 1) as f64 / (K - 2) as f64
    );
    println!(
        "  at photons, own photon left out     {:.4}",
        without_own / count as f64 / exact
    );
    println!(
        "  one sample per cell, other samples  {:.4}",
        other_samples / c / exact
    );
    println!(
        "  one sample per cell, non-samples    {:.4}",
        non_samples / c / exact
    );
}
