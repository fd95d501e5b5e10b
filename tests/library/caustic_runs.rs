//! Caustic passes on `cornell-glass`: the same photons for every thread
//! count, batch size and shard split; only caustic photons stored, none on
//! a mirror or glass; an empty pass without specular objects; a pass over
//! the memory budget refused before tracing.

use adaptive_pm::embree::Device;
use adaptive_pm::engine::caustic_aim::CausticAim;
use adaptive_pm::engine::{default_caustic_photons, Budget, Mode, Shard, TraceConfig, Tracer};
use adaptive_pm::photon_map::PhotonRecord;
use adaptive_pm::scene::Scene;

fn cornell_glass() -> Tracer<adaptive_pm::embree::CommittedScene> {
    let scene = Scene::open(adaptive_pm::scene::BUILTIN_CORNELL_GLASS).unwrap();
    Tracer::new(scene.commit(&Device::new().unwrap()).unwrap())
}

#[test]
fn the_pass_is_deterministic_across_threads_batches_and_shards() {
    let tracer = cornell_glass();
    let mut cfg = TraceConfig::new(Mode::Adaptive, Budget::NMax(1000));
    cfg.seed = 5;
    let n = 40_000;
    let run = |threads: usize, batch: usize, shard: Shard| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut c = cfg.clone();
        c.batch = batch;
        c.shard = shard;
        pool.install(|| tracer.trace_caustic(&c, n)).unwrap()
    };
    let one = run(1, 1024, Shard::WHOLE);
    let two = run(2, 7, Shard::WHOLE);
    assert!(one.report.stored > 1000, "{:?}", one.report);
    assert_eq!(one.photons, two.photons);
    assert_eq!(one.report.aimed, two.report.aimed);
    assert_eq!(one.into_map_checksum(), two.into_map_checksum());
    // Two shards store exactly the whole pass's photons (positions and
    // depths; each shard has its own power frame).
    // Waves are cut from each shard's own ids, so the order differs.
    let sorted = |mut v: Vec<PhotonRecord>| {
        v.sort_by(|a, b| {
            let key = |r: &PhotonRecord| (r.position.to_array(), r.depth);
            key(a).partial_cmp(&key(b)).unwrap()
        });
        v
    };
    let whole = sorted(run(2, 1024, Shard::WHOLE).records());
    let mut parts = sorted(
        (0..2)
            .flat_map(|i| run(2, 100, Shard::new(i, 2).unwrap()).records())
            .collect(),
    );
    assert_eq!(parts.len(), whole.len());
    for (a, b) in parts.iter_mut().zip(&whole) {
        assert_eq!((a.position, a.depth), (b.position, b.depth));
        let tol = 4.0 / 512.0 * b.power.max_element();
        assert!(
            (a.power - b.power).abs().max_element() <= tol,
            "{} vs {}",
            a.power,
            b.power
        );
    }
}

/// Checksum helper: the map's hash of the pass's photons.
trait MapChecksum {
    fn into_map_checksum(self) -> u64;
}

impl MapChecksum for adaptive_pm::engine::CausticOutput {
    fn into_map_checksum(self) -> u64 {
        self.into_map().checksum()
    }
}

#[test]
fn the_pass_stores_only_caustic_photons_off_specular_surfaces() {
    let tracer = cornell_glass();
    let cfg = TraceConfig::new(Mode::Adaptive, Budget::NMax(1000));
    let out = tracer.trace_caustic(&cfg, 20_000).unwrap();
    assert!(out.report.stored > 500, "{:?}", out.report);
    assert_eq!(out.report.targets, 2);
    assert!(out.photons.iter().all(|p| p.is_caustic() && p.depth() >= 1));
    // Every stored photon lies outside both spheres' meshes' bounds
    // (on the box, not on a mirror or glass).
    let aim = CausticAim::new(tracer.scene());
    for r in out.records() {
        for t in aim.targets() {
            let inside = (r.position - t.centre).length() < 0.95 * t.radius;
            assert!(!inside, "stored at {} inside target {:?}", r.position, t);
        }
    }
}

#[test]
fn a_scene_without_specular_objects_makes_an_empty_pass() {
    let scene = Scene::open(adaptive_pm::scene::BUILTIN_CORNELL_EMPTY).unwrap();
    assert_eq!(default_caustic_photons(&scene, 1_000_000), 0);
    let tracer = Tracer::new(scene.commit(&Device::new().unwrap()).unwrap());
    let out = tracer
        .trace_caustic(&TraceConfig::default(), 10_000)
        .unwrap();
    assert_eq!(
        (out.report.emitted, out.report.stored, out.report.targets),
        (0, 0, 0)
    );
    assert!(out.into_map().is_empty());
    let glass = Scene::open(adaptive_pm::scene::BUILTIN_CORNELL_GLASS).unwrap();
    assert!(default_caustic_photons(&glass, 1_000_000) > 0);
}

#[test]
fn a_pass_over_the_memory_budget_is_refused_before_tracing() {
    let tracer = cornell_glass();
    let cfg = TraceConfig {
        memory_budget: Some(1 << 20),
        ..TraceConfig::default()
    };
    let e = tracer.trace_caustic(&cfg, 1_000_000).unwrap_err();
    assert!(
        matches!(
            e,
            adaptive_pm::Error::Budget {
                photons: 1_000_000,
                ..
            }
        ),
        "{e}"
    );
    assert!(tracer.trace_caustic(&cfg, 1000).is_ok());
}
