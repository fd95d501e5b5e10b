//! How far room A's photon lookups reach into room B in the `door` scene
//! (docs/scenes.md, "The built-in `door`"): for 400 points on room A's
//! floor, the share of the k = 100 nearest facing photons (the renderer's
//! default k and largest radius) that lie in room B, at two budgets.
//!
//! `cargo run --release --example door_leak`

use adaptive_pm::embree::Device;
use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
use adaptive_pm::photon_map::PhotonMap;
use adaptive_pm::render::{default_max_radius, DEFAULT_K};
use adaptive_pm::scene::{Scene, BUILTIN_DOOR};
use glam::Vec3;
use std::sync::Arc;

/// Room B starts past the partition (tools/make_door.py).
const ROOM_B_X: f32 = 415.0;

fn main() -> adaptive_pm::Result<()> {
    let scene = Scene::open(BUILTIN_DOOR)?;
    let radius = default_max_radius(&scene);
    let prepared = Arc::new(scene.commit(&Device::new()?)?);
    for n_max in [20_000u64, 1_000_000] {
        let mut cfg = TraceConfig::new(Mode::Adaptive, Budget::NMax(n_max));
        cfg.seed = 1;
        let records = Tracer::new(Arc::clone(&prepared)).trace(&cfg)?.records();
        let map = PhotonMap::build(&records);
        let (mut from_b, mut found, mut kth) = (0usize, 0usize, 0.0f64);
        let mut out = Vec::new();
        for i in 0..400 {
            let (u, v) = ((i % 20) as f32 / 19.0, (i / 20) as f32 / 19.0);
            let p = Vec3::new(5.0 + 390.0 * u, 0.0, 5.0 + 390.0 * v);
            map.nearest_k_facing(p, Vec3::Y, DEFAULT_K, radius, &mut out);
            found += out.len();
            from_b += out
                .iter()
                .filter(|n| map.photon(n.index).position.x > ROOM_B_X)
                .count();
            kth += out.last().map_or(0.0, |n| f64::from(n.dist2).sqrt());
        }
        let in_a = records.iter().filter(|r| r.position.x < 400.0).count();
        println!(
            "N_MAX {n_max}: {} photons, {in_a} in room A; room A floor lookups (k = {DEFAULT_K}, \
             radius <= {radius:.1}): {:.3} of the photons returned lie in room B, mean k-th \
             distance {:.1}",
            records.len(),
            from_b as f64 / found.max(1) as f64,
            kth / 400.0
        );
    }
    Ok(())
}
