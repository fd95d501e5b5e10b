//! The photon map's kd-tree against kiddo 6's immutable kd-tree (the crate a user
//! would otherwise pick): builds of 1e4..1e6 uniform random photons (1e7 with
//! `KDTREE_BENCH_10M=1`: slow on a shared machine) on the same rayon pool size on
//! both sides (1 and 2 threads), then k = 50 nearest and radius queries on 1M.
//!
//! Ours builds in place from photons already compact (what the tracer hands over:
//! `PhotonMap::from_compact`, the copy made in the untimed setup); kiddo builds from
//! `[f32; 3]` points with `u32` items (its default `ImmutableKdTree<f32, 3>`:
//! Eytzinger stems, 32-point leaves) and allocates its own arrays. Ours fills a
//! reused `Vec`, kiddo returns a new `Vec` per query (its API). Radius: about 50
//! photons expected within r; kiddo's unsorted form, ours unsorted too.

use adaptive_pm::embree::thread_pool;
use adaptive_pm::photon_map::PhotonMap;
use criterion::{criterion_group, criterion_main, BatchSize, BenchmarkId, Criterion, Throughput};
use glam::Vec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use std::hint::black_box;
use std::num::NonZero;
use std::time::Duration;

#[path = "common/uniform_photons.rs"]
mod uniform_photons;
use uniform_photons::{compact, points, records};

type Kiddo = ImmutableKdTree<f32, 3>;

const K: usize = 50;
const QUERIES: usize = 2000;

fn build(c: &mut Criterion) {
    let mut group = c.benchmark_group("build");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(3));
    group.warm_up_time(Duration::from_millis(300));
    let mut sizes = vec![10_000, 100_000, 1_000_000];
    if std::env::var_os("KDTREE_BENCH_10M").is_some() {
        sizes.push(10_000_000);
    }
    for threads in [1, 2] {
        let pool = thread_pool(threads).unwrap();
        for &n in &sizes {
            let recs = records(n, 1);
            let pts = points(&recs);
            let (photons, frame) = compact(&recs);
            let id = format!("{n}/{threads}t");
            group.throughput(Throughput::Elements(n as u64));
            group.bench_function(BenchmarkId::new("photon_map", &id), |b| {
                b.iter_batched(
                    || photons.clone(),
                    |v| pool.install(|| PhotonMap::from_compact(v, frame)),
                    BatchSize::LargeInput,
                )
            });
            group.bench_function(BenchmarkId::new("kiddo", &id), |b| {
                b.iter(|| pool.install(|| Kiddo::new_from_slice(black_box(&pts)).unwrap()))
            });
        }
    }
    group.finish();
}

fn queries_1m(c: &mut Criterion) {
    let n = 1_000_000;
    let recs = records(n, 1);
    let (photons, frame) = compact(&recs);
    let map = PhotonMap::from_compact(photons, frame);
    let tree = Kiddo::new_from_slice(&points(&recs)).unwrap();
    let queries: Vec<Vec3> = records(QUERIES, 2).iter().map(|r| r.position).collect();
    // About K photons expected in the ball: (4/3) pi r^3 n = K.
    let radius = (K as f32 * 3.0 / (4.0 * std::f32::consts::PI * n as f32)).cbrt();

    let mut group = c.benchmark_group("queries_of_1M");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(3));
    group.warm_up_time(Duration::from_millis(300));
    group.throughput(Throughput::Elements(QUERIES as u64));
    group.bench_function("nearest_50/photon_map", |b| {
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
    let k = NonZero::new(K).unwrap();
    group.bench_function("nearest_50/kiddo", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for q in &queries {
                let res = tree
                    .query(&q.to_array())
                    .nearest_n::<SquaredEuclidean<f32>>(k)
                    .execute();
                acc += res[K - 1].distance;
            }
            acc
        })
    });
    group.bench_function("radius/photon_map", |b| {
        let mut out = Vec::with_capacity(2 * K);
        b.iter(|| {
            let mut count = 0;
            for &q in &queries {
                map.within_radius(q, radius, &mut out);
                count += out.len();
            }
            count
        })
    });
    group.bench_function("radius/kiddo", |b| {
        b.iter(|| {
            let mut count = 0;
            for q in &queries {
                let res = tree
                    .query(&q.to_array())
                    .within::<SquaredEuclidean<f32>>(radius * radius)
                    .unsorted()
                    .execute();
                count += res.len();
            }
            count
        })
    });
    group.finish();
}

// No plots: criterion's plotters backend needs a system font, which these
// machines lack (it panicked after the first measurement); the numbers are
// in the terminal and in target/criterion.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = build, queries_1m
}
criterion_main!(benches);
