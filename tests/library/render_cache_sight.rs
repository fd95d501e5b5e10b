//! The irradiance cache where a surface runs on out of its points' sight,
//! under a block. Its estimates admit only the photons their point sees
//! along its plane, and divide by the part of the disc it sees. (The same
//! sight keeps a cell from reading the next room under a partition:
//! `render::cache`'s unit test on `door`'s floor.)

use crate::render_cache::{block_of, block_sums, ratio_and_se, roofed, uniform_floor_photons};
use adaptive_pm::embree::Device;
use adaptive_pm::photon_map::{PhotonMap, PhotonRecord};
use adaptive_pm::raycast::RayCaster;
use adaptive_pm::render::{default_max_radius, CacheConfig, IrradianceCache, Lookup};
use adaptive_pm::rng::Rng;
use adaptive_pm::scene::Scene;
use glam::Vec3;

/// The cache (k = 100, stride 8) of `records` in `scene`.
fn cache_of(scene: &Scene, records: &[PhotonRecord]) -> IrradianceCache {
    let prepared = scene.clone().commit(&Device::new().unwrap()).unwrap();
    let lookup = Lookup {
        k: 100,
        max_radius: default_max_radius(scene),
    };
    let cfg = CacheConfig { stride: 8, lookup };
    IrradianceCache::build(&PhotonMap::build(records), &prepared, &cfg).unwrap()
}

/// `cache / exact - 1` over `points` (each with its batch block), 4
/// jittered lookups a point, and its standard error from batch means; the
/// misses counted apart.
fn relative_error(
    cache: &IrradianceCache,
    points: &[(Vec3, (i64, i64))],
    exact: f64,
    rng: &mut Rng,
) -> (f64, f64, usize, usize) {
    let (mut lookups, mut misses) = (Vec::new(), 0);
    for &(p, block) in points {
        for _ in 0..4 {
            let u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
            match cache.irradiance(p, Vec3::Y, u) {
                Some(e) => lookups.push((block, e.x as f64 / exact, 1.0)),
                None => misses += 1,
            }
        }
    }
    let (mean, se) = ratio_and_se(&block_sums(&lookups));
    (mean, se, lookups.len(), misses)
}

/// Points on the Cornell floor at `d` from the blocks' sides, along the
/// middle 80 % of each side's foot, one every 2 units, with their batch
/// blocks of 50 units.
fn block_feet(scene: &Scene, rt: &dyn RayCaster, d: f32, top: f32) -> Vec<(Vec3, (i64, i64))> {
    let mut points = Vec::new();
    for mesh in scene.meshes().iter().filter(|m| m.name.contains("block")) {
        for i in 0..mesh.indices.len() {
            let t = mesh.triangle(i);
            let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
            let foot: Vec<Vec3> = t.into_iter().filter(|v| v.y.abs() < 1e-3).collect();
            if n.y.abs() > 0.1 || foot.len() != 2 {
                continue;
            }
            let along = foot[1] - foot[0];
            let count = (0.8 * along.length() / 2.0) as usize;
            for k in 0..count {
                let on = foot[0] + along * (0.1 + 0.8 * (k as f32 + 0.5) / count as f32);
                // The side's outward normal: open floor on its side, the
                // block on the other.
                for out in [n, -n] {
                    let p = Vec3::new(on.x, 0.0, on.z) + Vec3::new(out.x, 0.0, out.z) * d;
                    if !roofed(rt, p, top) && roofed(rt, on - out, top) {
                        points.push((p, block_of(p, 50.0)));
                    }
                }
            }
        }
    }
    points
}

/// Photons spread evenly over the Cornell floor where photons can land
/// (none under the blocks), read at the blocks' feet, 0.05 to 2 cell sides
/// from their sides. Beside a side the disc runs on over the floor under
/// the block, where no photon is: an estimate that divided by that part of
/// the disc read low, -12 % at half a radius and about -45 % at the foot
/// (the floor runs on, so only the centre's sight tells the part apart).
/// `sum cache / sum exact - 1` must be 0 within 4 sigma, sigma from batch
/// means over blocks of 50 units; under 5 % of the lookups may miss.
#[test]
fn cache_is_unbiased_at_a_blocks_foot() {
    let scene = Scene::cornell().unwrap();
    let (_, hi) = scene.bounds();
    let mut rng = Rng::new(crate::common::seed(23));
    let (all, area) = uniform_floor_photons(&scene, 300_000, &mut rng);
    let prepared = scene.clone().commit(&Device::new().unwrap()).unwrap();
    let rt = prepared.caster();
    let landed: Vec<PhotonRecord> = all
        .into_iter()
        .filter(|p| !roofed(rt, p.position, hi.y))
        .collect();
    let exact = 300_000.0 / f64::from(area);
    let cache = cache_of(&scene, &landed);
    let h = cache.cell_size();
    let points: Vec<_> = [0.05, 0.5, 1.0, 2.0]
        .into_iter()
        .flat_map(|f| block_feet(&scene, rt, f * h, hi.y))
        .collect();
    assert!(points.len() > 400, "{} points at the feet", points.len());
    let (mean, se, n, misses) = relative_error(&cache, &points, exact, &mut rng);
    eprintln!(
        "at the blocks' feet: cache / exact - 1 = {mean:+.4} +- {se:.4} over {n} lookups, \
         {misses} misses (h {h:.1})"
    );
    assert!(misses * 20 < n, "{misses} misses");
    crate::common::assert_sigmas("cache / exact at the blocks' feet", mean, se, 4.0);
}
