//! The photon map's kd-tree against kiddo's immutable kd-tree (the crate a user would
//! otherwise pick), in the same groups: build, and k = 50 nearest neighbours, on
//! 1M uniform random photons; plus a build-size sweep.
//!
//! Ours builds from `PhotonRecord`s (bounds + quantisation to 16-byte photons
//! included); kiddo builds from `[f32; 3]` points with `u32` items and 32-point
//! leaves. Ours fills a reused `Vec`, kiddo returns a new `Vec` per query (its API).

use adaptive_pm::photon_map::{GrowingMap, PhotonMap, PhotonRecord};
use adaptive_pm::rng::Rng;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::Vec3;
use kiddo::immutable::float::kdtree::ImmutableKdTree;
use kiddo::SquaredEuclidean;
use std::hint::black_box;
use std::time::Duration;

type Kiddo = ImmutableKdTree<f32, u32, 3, 32>;

const K: usize = 50;
const QUERIES: usize = 2000;

fn records(n: usize, seed: u64) -> Vec<PhotonRecord> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| PhotonRecord {
            position: Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()),
            power: Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()),
            direction: Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5,
            depth: (rng.next_u32() % 4) as u8,
        })
        .collect()
}

fn points(records: &[PhotonRecord]) -> Vec<[f32; 3]> {
    records.iter().map(|r| r.position.to_array()).collect()
}

fn build(c: &mut Criterion) {
    let mut group = c.benchmark_group("build");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(4));
    group.warm_up_time(Duration::from_millis(500));
    for n in [10_000, 100_000, 1_000_000] {
        let recs = records(n, 1);
        let pts = points(&recs);
        group.throughput(Throughput::Elements(n as u64));
        group.bench_with_input(BenchmarkId::new("photon_map", n), &recs, |b, r| {
            b.iter(|| PhotonMap::build(black_box(r)))
        });
        group.bench_with_input(BenchmarkId::new("kiddo", n), &pts, |b, p| {
            b.iter(|| Kiddo::new_from_slice(black_box(p)))
        });
    }
    group.finish();
}

fn nearest_50(c: &mut Criterion) {
    let n = 1_000_000;
    let recs = records(n, 1);
    let map = PhotonMap::build(&recs);
    let tree = Kiddo::new_from_slice(&points(&recs));
    let queries: Vec<Vec3> = records(QUERIES, 2).iter().map(|r| r.position).collect();

    let mut group = c.benchmark_group("nearest_50_of_1M");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(4));
    group.warm_up_time(Duration::from_millis(500));
    group.throughput(Throughput::Elements(QUERIES as u64));
    group.bench_function("photon_map", |b| {
        let mut out = Vec::with_capacity(K);
        b.iter(|| {
            let mut acc = 0.0;
            for &q in &queries {
                map.nearest_k(q, K, f32::INFINITY, &mut out);
                acc += out[K - 1].dist2;
            }
            acc
        })
    });
    group.bench_function("kiddo", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for q in &queries {
                let res = tree.nearest_n::<SquaredEuclidean>(&q.to_array(), K);
                acc += res[K - 1].distance;
            }
            acc
        })
    });
    group.finish();
}

/// Density control's loop on a growing map: before each insertion, the 10 nearest
/// photons of the new one (200k photons on the unit square, cells sized so that
/// about 10 photons of the final map fall within one cell's radius).
fn growing_map(c: &mut Criterion) {
    let n = 200_000;
    let recs: Vec<PhotonRecord> = records(n, 3)
        .into_iter()
        .map(|mut r| {
            r.position.z = 0.0;
            r
        })
        .collect();
    let cell = (10.0 / (std::f32::consts::PI * n as f32)).sqrt();
    let mut group = c.benchmark_group("growing_map_200k");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(4));
    group.warm_up_time(Duration::from_millis(500));
    group.throughput(Throughput::Elements(n as u64));
    group.bench_function("query_10_then_insert", |b| {
        b.iter(|| {
            let mut map = GrowingMap::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), cell).unwrap();
            let mut out = Vec::with_capacity(10);
            for r in &recs {
                map.nearest_k(r.position, 10, f32::INFINITY, &mut out);
                map.insert(*r);
            }
            map.len()
        })
    });
    group.finish();
}

criterion_group!(benches, build, nearest_50, growing_map);
criterion_main!(benches);
