//! The kd-tree against kiddo 6, in rounds that alternate the two sides in one
//! process: on a shared or virtual machine both speeds drift by tens of
//! percent from minute to minute, so criterion's medians, taken one side
//! after the other, can differ by more than the two trees do. A ratio taken
//! within one round, and the median over the rounds, drifts much less.
//!
//! Each round times, on one thread: builds of 1e4, 1e5 and 1e6 uniform random
//! photons (ours in place from compact photons, as the tracer hands them over;
//! kiddo's `ImmutableKdTree<f32, 3>` from `[f32; 3]`, as in `benches/kdtree.rs`),
//! then 2000 k = 50 and radius queries (about 50 found) in the 1M map.
//!
//! `cargo bench --bench kdtree_vs_kiddo -- [ROUNDS]` (default 7; it lives
//! in the bench crate beside criterion's benches, so that kiddo is not built
//! with the test suite) prints each round's times and ratios (ours / kiddo: below 1, ours is
//! faster) and the median ratio of each row.
//!
//! `cargo bench --bench kdtree_vs_kiddo -- builds ours|kiddo N COUNT` (or the
//! binary it builds under `target/release/deps/`) only builds COUNT trees of N
//! photons on one thread, for counting instructions, which drift much less
//! than times: run it under `valgrind --tool=cachegrind --cache-sim=no` with
//! COUNT = 20 and COUNT = 0 (the setup alone) and divide the difference of
//! the `I refs` by 20.

use adaptive_pm::embree::thread_pool;
use adaptive_pm::photon_map::{CompactPhoton, PhotonMap};
use glam::Vec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use std::hint::black_box;
use std::num::NonZero;
use std::time::Instant;

#[path = "common/uniform_photons.rs"]
mod uniform_photons;
use uniform_photons::{compact, points, records, unit_frame};

type Kiddo = ImmutableKdTree<f32, 3>;
const K: usize = 50;
const QUERIES: usize = 2000;

/// Seconds per run of `f`, the best of as many runs as fit in about 0.3 s.
fn time<T>(mut f: impl FnMut() -> T) -> f64 {
    time_with(|| (), |()| f())
}

/// Seconds per run of `f` on a fresh `setup()` (not timed), the best of as
/// many runs as fit in about 0.3 s.
fn time_with<I, T>(mut setup: impl FnMut() -> I, mut f: impl FnMut(I) -> T) -> f64 {
    let mut best = f64::INFINITY;
    let start = Instant::now();
    let mut runs = 0;
    while runs < 3 || (start.elapsed().as_secs_f64() < 0.3 && runs < 1000) {
        let input = setup();
        let t = Instant::now();
        black_box(f(input));
        best = best.min(t.elapsed().as_secs_f64());
        runs += 1;
    }
    best
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// `builds ours|kiddo N COUNT`: COUNT one-thread builds of N photons.
fn builds(args: &[String]) {
    let (Some(side), Some(Ok(n)), Some(Ok(count))) = (
        args.first(),
        args.get(1).map(|s| s.parse::<usize>()),
        args.get(2).map(|s| s.parse::<usize>()),
    ) else {
        eprintln!("usage: kdtree_vs_kiddo builds ours|kiddo N COUNT");
        std::process::exit(2)
    };
    let pool = thread_pool(1).expect("a one-thread pool");
    let recs = records(n, 1);
    let mut size = 0;
    if side == "ours" {
        let (photons, frame) = compact(&recs);
        let mut buffer = photons.clone();
        for _ in 0..count {
            buffer.clear();
            buffer.extend_from_slice(&photons);
            let map = pool.install(|| PhotonMap::from_compact(std::mem::take(&mut buffer), frame));
            size += map.len();
            buffer = map.into_compact().0;
        }
    } else {
        let points = points(&recs);
        for _ in 0..count {
            size += pool.install(|| Kiddo::new_from_slice(&points).map_or(0, |t| t.size()));
        }
    }
    println!("{count} builds of {n} photons ({side}): {size} photons in all");
}

fn main() {
    // `cargo bench` appends `--bench` to the arguments.
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    if args.first().map(String::as_str) == Some("builds") {
        return builds(&args[1..]);
    }
    let rounds: usize = match args.first() {
        None => 7,
        Some(s) => s.parse().unwrap_or_else(|_| {
            eprintln!("ROUNDS: {s:?} is not a number");
            std::process::exit(2)
        }),
    };
    let pool = thread_pool(1).expect("a one-thread pool");
    let frame = unit_frame();
    let sets: Vec<(String, Vec<CompactPhoton>, Vec<[f32; 3]>)> = [10_000, 100_000, 1_000_000]
        .iter()
        .map(|&n| {
            let recs = records(n, 1);
            (
                format!("build {}k", n / 1000),
                compact(&recs).0,
                points(&recs),
            )
        })
        .collect();
    let (_, big_compact, big_points) = &sets[2];
    let map = PhotonMap::from_compact(big_compact.clone(), frame);
    let tree = Kiddo::new_from_slice(big_points).expect("kiddo builds");
    let queries: Vec<Vec3> = records(QUERIES, 2).iter().map(|r| r.position).collect();
    let radius = (K as f32 * 3.0 / (4.0 * std::f32::consts::PI * 1e6)).cbrt();
    let k = NonZero::new(K).expect("K > 0");

    let mut rows: Vec<(String, Vec<f64>)> = Vec::new();
    for round in 0..rounds {
        let mut line = Vec::new();
        for (label, compact, points) in &sets {
            let ours = pool
                .install(|| time_with(|| compact.clone(), |c| PhotonMap::from_compact(c, frame)));
            let theirs = pool.install(|| time(|| Kiddo::new_from_slice(points).map(|t| t.size())));
            line.push((label.clone(), ours, theirs));
        }
        let mut out = Vec::with_capacity(K);
        let ours = time(|| {
            queries.iter().fold(0.0, |acc, &q| {
                map.nearest_k(q, K, f32::INFINITY, &mut out);
                acc + out[K - 1].dist2
            })
        });
        let theirs = time(|| {
            queries.iter().fold(0.0, |acc, q| {
                let res = tree
                    .query(&q.to_array())
                    .nearest_n::<SquaredEuclidean<f32>>(k)
                    .execute();
                acc + res[K - 1].distance
            })
        });
        line.push(("2000 queries k = 50 in 1M".into(), ours, theirs));
        let ours = time(|| {
            queries.iter().fold(0, |acc, &q| {
                map.within_radius(q, radius, &mut out);
                acc + out.len()
            })
        });
        let theirs = time(|| {
            queries.iter().fold(0, |acc, q| {
                let res = tree
                    .query(&q.to_array())
                    .within::<SquaredEuclidean<f32>>(radius * radius)
                    .unsorted()
                    .execute();
                acc + res.len()
            })
        });
        line.push(("2000 radius queries (~50 found) in 1M".into(), ours, theirs));
        println!("round {round}");
        for (i, (label, ours, theirs)) in line.into_iter().enumerate() {
            println!(
                "  {label:<40} ours {:>9.3} ms  kiddo {:>9.3} ms  {:.2}",
                ours * 1e3,
                theirs * 1e3,
                ours / theirs
            );
            if rows.len() <= i {
                rows.push((label, Vec::new()));
            }
            rows[i].1.push(ours / theirs);
        }
    }
    println!("\n| one thread | ours / kiddo, median of {rounds} rounds | range |");
    println!("|---|---|---|");
    for (label, ratios) in rows {
        let (lo, hi) = ratios
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &r| (a.min(r), b.max(r)));
        println!("| {label} | {:.2} | {lo:.2}–{hi:.2} |", median(ratios));
    }
}
