//! How far the irradiance cache's lookups read across `door`'s partition
//! (docs/rendering.md, "Cells a wall crosses"): photons of power 1 spread
//! evenly over both rooms' floors, the lit room (x > 415) 20 times as dense
//! as the camera's (x < 400); the cache (k = 100, stride 8) read at points
//! of the camera's room 0.05 to 1 kernel radius from the partition and over
//! 50 from the doorway, 4 jittered lookups each. Prints, per distance, the
//! cache's mean over the camera room's exact irradiance: 9.0, 2.0, 1.14 and
//! 1.02 at 0.05, 0.25, 0.5 and 1 radius before the cache's walled cells,
//! 1.02, 1.00, 1.01 and 1.02 with them.
//!
//! `cargo run --release --example door_cache_leak`

use adaptive_pm::embree::Device;
use adaptive_pm::photon_map::{PhotonMap, PhotonRecord};
use adaptive_pm::render::{default_max_radius, CacheConfig, IrradianceCache, Lookup};
use adaptive_pm::rng::Rng;
use adaptive_pm::scene::{Scene, BUILTIN_DOOR};
use glam::Vec3;

/// `count` photons of power 1 over the floor from `x0` to `x1`, z 0 to 400.
fn floor(x0: f32, x1: f32, count: usize, rng: &mut Rng) -> Vec<PhotonRecord> {
    (0..count)
        .map(|_| {
            let [u, v] = rng.next_2d();
            PhotonRecord {
                position: Vec3::new(x0 + (x1 - x0) * u, 0.0, 400.0 * v),
                power: Vec3::ONE,
                direction: -Vec3::Y,
                depth: 0,
                caustic: false,
            }
        })
        .collect()
}

fn main() -> adaptive_pm::Result<()> {
    let scene = Scene::open(BUILTIN_DOOR)?;
    let prepared = scene.clone().commit(&Device::new()?)?;
    let mut rng = Rng::new(29);
    let dim = 6_000;
    let mut records = floor(0.0, 400.0, dim, &mut rng);
    records.extend(floor(415.0, 815.0, 20 * dim, &mut rng));
    let exact = dim as f64 / (400.0 * 400.0);
    let lookup = Lookup {
        k: 100,
        max_radius: default_max_radius(&scene),
    };
    let cfg = CacheConfig { stride: 8, lookup };
    let cache = IrradianceCache::build(&PhotonMap::build(&records), &prepared, &cfg)?;
    let radius = (100.0 / (std::f64::consts::PI * exact * 7.0 / 8.0)).sqrt() as f32;
    println!(
        "kernel radius {radius:.1}, cell side {:.1}",
        cache.cell_size()
    );
    println!("radii from the partition | cache / exact");
    for f in [0.05f32, 0.25, 0.5, 1.0] {
        let (mut sum, mut n) = (0.0, 0usize);
        for i in 0..120 {
            for z in [10.0 + i as f32, 390.0 - i as f32] {
                let p = Vec3::new(400.0 - f * radius, 0.0, z);
                for _ in 0..4 {
                    let u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
                    if let Some(e) = cache.irradiance(p, Vec3::Y, u, prepared.caster()) {
                        sum += f64::from(e.x) / exact;
                        n += 1;
                    }
                }
            }
        }
        println!("{f:.2} | {:.2}", sum / n.max(1) as f64);
    }
    Ok(())
}
