//! The three modes compared in one criterion group on the Cornell box at
//! n = 0, 20, 200 (throughput = photons emitted), and the two steps after a
//! trace: the kd-tree builds (`Maps::build`) and the density evaluation
//! (`measure`) of the full and primary maps.
//!
//! N_MAX = 20 000 keeps the run to a few minutes (density control is the slow
//! mode); the Cornell sweep times N_MAX = 1e5. The density mode's target is the
//! experiments' one: the classic mode's mean density with a diffuse light.
//!
//! `cargo bench --bench modes -- --noplot`

use adaptive_pm::embree::Device;
use adaptive_pm::emitter::CosN;
use adaptive_pm::engine::{
    density_points, map_metrics, Budget, DensityTarget, Maps, Mode, TraceConfig, Tracer,
};
use adaptive_pm::scene::{PreparedScene, Scene};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::time::Duration;

const N_MAX: u64 = 20_000;
const EXPONENTS: [f32; 3] = [0.0, 20.0, 200.0];

fn modes(c: &mut Criterion) {
    let device = Device::new().unwrap();
    let scenes: Vec<Scene> = EXPONENTS
        .iter()
        .map(|&n| {
            let mut s = Scene::cornell().unwrap();
            s.set_cosn(CosN::new(n).unwrap());
            s
        })
        .collect();
    // one committed geometry serves every exponent: only the emission changes
    let rt = scenes[0].embree_geometry(&device).unwrap();
    let points = density_points(&scenes[0]);

    let classic = TraceConfig::new(Mode::Classic, Budget::NMax(N_MAX));
    let reference = Tracer::new(PreparedScene::new(scenes[0].clone(), &rt).unwrap())
        .trace(&classic)
        .unwrap();
    let ref_maps = Maps::from_photons(reference.photons.clone(), reference.frame);
    let target = map_metrics(&ref_maps, &points).full.mean;

    let mut group = c.benchmark_group("modes");
    for (scene, n) in scenes.iter().zip(EXPONENTS) {
        let tracer = Tracer::new(PreparedScene::new(scene.clone(), &rt).unwrap());
        for mode in Mode::ALL {
            let mut cfg = TraceConfig::new(mode, Budget::NMax(N_MAX));
            if mode == Mode::Density {
                cfg.density_target = DensityTarget::PerArea(target);
            }
            // one untimed run: the emitted count, and the analyses cached
            let emitted = tracer.trace(&cfg).unwrap().report.emitted;
            group.throughput(Throughput::Elements(emitted));
            group.bench_with_input(BenchmarkId::new(mode.name(), n), &cfg, |b, cfg| {
                b.iter(|| tracer.trace(cfg).unwrap().report.stored)
            });
        }
    }
    group.finish();

    let mut group = c.benchmark_group("maps");
    for (scene, n) in scenes.iter().zip(EXPONENTS) {
        for mode in [Mode::Classic, Mode::Adaptive] {
            let out = Tracer::new(PreparedScene::new(scene.clone(), &rt).unwrap())
                .trace(&TraceConfig::new(mode, Budget::NMax(N_MAX)))
                .unwrap();
            let id = format!("{}/{n}", mode.name());
            group.throughput(Throughput::Elements(out.photons.len() as u64));
            group.bench_function(BenchmarkId::new("build", &id), |b| {
                b.iter(|| {
                    Maps::from_photons(out.photons.clone(), out.frame)
                        .full
                        .len()
                })
            });
            let maps = Maps::from_photons(out.photons.clone(), out.frame);
            group.throughput(Throughput::Elements(2 * points.len() as u64));
            group.bench_function(BenchmarkId::new("measure", &id), |b| {
                b.iter(|| map_metrics(&maps, &points).full.max)
            });
        }
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .without_plots()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
        .without_plots();
    targets = modes
}
criterion_main!(benches);
