//! The share of stored photons that a render's lookups read
//! (`render::reads`, issue 27): 0 for photons no lookup can reach, 1 when
//! every lookup returns every photon, the exact fraction of a mix of both,
//! the same on any thread count, and the image of a plain render.

use adaptive_pm::embree::Device;
use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
use adaptive_pm::photon_map::PhotonRecord;
use adaptive_pm::render::{render, render_reading, MapReads, RenderConfig, RenderMaps};
use adaptive_pm::rng::Rng;
use adaptive_pm::scene::{Scene, BUILTIN_CORNELL_EMPTY};
use glam::Vec3;
use std::sync::Arc;

/// `n` indirect photons (depth 1) on the floor of the empty box, arriving
/// from above, when `on_floor`; else as many 10^4 units below it, beyond
/// every lookup's radius and off every surface.
fn photons(n: usize, on_floor: bool, seed: u64) -> Vec<PhotonRecord> {
    let mut rng = Rng::new(seed);
    let y = if on_floor { 0.0 } else { -1e4 };
    (0..n)
        .map(|_| {
            let [u, v] = rng.next_2d();
            PhotonRecord {
                position: Vec3::new(50.0 + 450.0 * u, y, 50.0 + 450.0 * v),
                power: Vec3::splat(1.0),
                direction: Vec3::new(0.1, -1.0, 0.2).normalize(),
                depth: 1,
                caustic: false,
            }
        })
        .collect()
}

/// The read share of a render of `records` at 16 x 16 with `k` photons per
/// lookup and no bound on the kernel radius, with and without the cache's
/// build lookups.
fn shares(records: &[PhotonRecord], k: usize, gather: u32) -> (f64, f64) {
    let device = Device::new().unwrap();
    let prepared = Scene::open(BUILTIN_CORNELL_EMPTY)
        .unwrap()
        .commit(&device)
        .unwrap();
    let maps = RenderMaps::build(records);
    let reads = MapReads::new(&maps);
    let mut rc = RenderConfig::new(16, 16);
    rc.spp = 2;
    rc.k = k;
    rc.final_gather = gather;
    rc.max_radius = Some(1e3);
    render_reading(&prepared, &reads, &rc).unwrap();
    let all = reads.share(records).unwrap();
    let pixels = reads.share_without_cache_build(records).unwrap();
    assert!(pixels <= all, "{pixels} > {all}");
    if gather == 0 {
        assert_eq!(pixels, all, "no cache without a gather");
    }
    (all, pixels)
}

fn share(records: &[PhotonRecord], k: usize, gather: u32) -> f64 {
    shares(records, k, gather).0
}

#[test]
fn photons_no_lookup_reaches_are_never_read() {
    // With a gather and its cache: no photon lies on a surface, so the cache
    // has no sample, and no gather or pixel lookup comes within 10^3.
    assert_eq!(share(&photons(300, false, 1), 50, 1), 0.0);
    assert_eq!(share(&photons(300, false, 2), 50, 0), 0.0);
}

#[test]
fn lookups_of_every_photon_read_them_all() {
    // Without a gather every floor pixel reads the indirect map, k = all.
    assert_eq!(share(&photons(300, true, 3), 300, 0), 1.0);
}

#[test]
fn a_mix_reads_exactly_the_reachable_part() {
    let mut records = photons(200, true, 4);
    records.extend(photons(600, false, 5));
    // k = 800: every lookup returns the 200 on the floor (the others are
    // beyond the radius).
    assert_eq!(share(&records, 800, 0), 0.25);
}

#[test]
fn marks_do_not_depend_on_threads_and_leave_the_image_alone() {
    let device = Device::new().unwrap();
    let scene = Scene::open(BUILTIN_CORNELL_EMPTY).unwrap();
    let prepared = Arc::new(scene.commit(&device).unwrap());
    let mut cfg = TraceConfig::new(Mode::Adaptive, Budget::NMax(5_000));
    cfg.seed = 9;
    let records = Tracer::new(Arc::clone(&prepared))
        .trace(&cfg)
        .unwrap()
        .records();
    let maps = RenderMaps::build(&records);
    let mut rc = RenderConfig::new(16, 16);
    rc.spp = 4;
    rc.k = 40;
    let plain = render(&prepared, Some(&maps), &rc).unwrap();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let reads = MapReads::new(&maps);
            let (image, _) = render_reading(&prepared, &reads, &rc).unwrap();
            let shares = (
                reads.share(&records).unwrap(),
                reads.share_without_cache_build(&records).unwrap(),
            );
            (image, reads.read_counts(), shares)
        })
    };
    let (one, two) = (run(1), run(2));
    let (pixel_reads, build_reads) = one.1;
    assert!(build_reads > 0 && pixel_reads.iter().sum::<usize>() > 0);
    assert_eq!(one.0.pixels, plain.pixels, "marking changes no pixel");
    assert_eq!(one.1, two.1, "marks per map");
    assert_eq!(one.2, two.2);
    eprintln!("read shares {:?} (per map, cache build {:?})", one.2, one.1);
    assert!(one.2 .1 > 0.0 && one.2 .1 <= one.2 .0 && one.2 .0 <= 1.0);
    // Records the maps were not built from are refused.
    assert!(reads_of_other_records_fail(&maps, &records));
}

fn reads_of_other_records_fail(maps: &RenderMaps, records: &[PhotonRecord]) -> bool {
    MapReads::new(maps).share(&records[1..]).is_err()
}
