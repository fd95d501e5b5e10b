//! Ray throughput of the three ways to trace, as `adaptive-pm bench rays`
//! reports it:
//!
//! - **raw**: one `apm_intersect1` shim call per ray on a hand-filled
//!   `RTCRayHit`, no validation, no conversion to [`Hit`](super::Hit): the
//!   `unsafe` baseline the wrapper is judged against;
//! - **single**: [`CommittedScene::intersect`] per ray;
//! - **batch**: [`CommittedScene::intersect_batch`] per chunk.
//!
//! Each path traces all rays once per repetition, split into fixed chunks of
//! [`CHUNK`] rays run in parallel on a pool of `threads` workers (FTZ/DAZ
//! set); one warm-up pass, then the best of [`REPETITIONS`] timed passes.
//! The three hit counts must agree, which both keeps the work observable and
//! checks that the wrapper changes nothing.
//!
//! Timed numbers for claims come from `benches/rays.rs` (criterion); this is
//! the quick, user-facing figure.

use std::time::Instant;

use rayon::prelude::*;

use super::scene::to_rtc_rayhit;
use super::{thread_pool, CommittedScene, Ray};
use crate::{Error, Result};
use embree_sys as sys;

/// Rays per parallel work item: large enough to amortise rayon's task cost,
/// small enough to balance 2-64 threads over 10^5-10^7 rays.
pub const CHUNK: usize = 4096;

/// Timed passes per path (the best one counts).
pub const REPETITIONS: usize = 3;

/// Result of [`measure_throughput`]: millions of rays per second per path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Throughput {
    /// Direct shim calls (the `unsafe` baseline).
    pub raw_mrays_per_s: f64,
    /// [`CommittedScene::intersect`] per ray.
    pub single_mrays_per_s: f64,
    /// [`CommittedScene::intersect_batch`] per chunk.
    pub batch_mrays_per_s: f64,
    /// Worker threads used.
    pub threads: usize,
    /// Rays traced per pass.
    pub rays: usize,
    /// Rays that hit something (the same for all three paths).
    pub hits: usize,
}

/// Hits of `rays` through direct shim calls.
fn raw_pass(scene: &CommittedScene, rays: &[Ray]) -> usize {
    rays.par_chunks(CHUNK)
        .map(|chunk| {
            let mut hits = 0;
            for ray in chunk {
                let mut rh = to_rtc_rayhit(ray);
                // SAFETY: the scene is committed and alive for the borrow;
                // `rh` is an initialised `RTCRayHit` owned by this thread.
                unsafe { sys::apm_intersect1(scene.raw(), &mut rh) };
                hits += usize::from(rh.hit.geomID != sys::RTC_INVALID_GEOMETRY_ID);
            }
            hits
        })
        .sum()
}

fn single_pass(scene: &CommittedScene, rays: &[Ray]) -> usize {
    rays.par_chunks(CHUNK)
        .map(|chunk| {
            chunk
                .iter()
                .filter(|r| scene.intersect(r).is_some())
                .count()
        })
        .sum()
}

fn batch_pass(scene: &CommittedScene, rays: &[Ray]) -> usize {
    rays.par_chunks(CHUNK)
        .map_init(
            || vec![None; CHUNK],
            |buf, chunk| {
                let hits = &mut buf[..chunk.len()];
                scene.intersect_batch(chunk, hits);
                hits.iter().filter(|h| h.is_some()).count()
            },
        )
        .sum()
}

/// Best-of-[`REPETITIONS`] rate in Mrays/s, after one warm-up, and the hit count.
fn time_pass(
    pool: &rayon::ThreadPool,
    rays: usize,
    pass: impl Fn() -> usize + Sync,
) -> (f64, usize) {
    let hits = pool.install(&pass);
    let mut best = f64::INFINITY;
    for _ in 0..REPETITIONS {
        let start = Instant::now();
        let h = pool.install(&pass);
        best = best.min(start.elapsed().as_secs_f64());
        debug_assert_eq!(h, hits);
    }
    let rate = if best > 0.0 {
        rays as f64 / best / 1e6
    } else {
        f64::INFINITY
    };
    (rate, hits)
}

/// Traces `rays` through the three paths on `threads` workers (0: all cores).
///
/// # Errors
/// [`Error::InvalidParameter`] when `rays` is empty or the pool cannot start;
/// [`Error::Embree`] (code 0) when the paths disagree on the number of hits.
pub fn measure_throughput(
    scene: &CommittedScene,
    rays: &[Ray],
    threads: usize,
) -> Result<Throughput> {
    if rays.is_empty() {
        return Err(Error::param("rays", "need at least one ray to measure"));
    }
    let pool = thread_pool(threads)?;
    let (raw, raw_hits) = time_pass(&pool, rays.len(), || raw_pass(scene, rays));
    let (single, single_hits) = time_pass(&pool, rays.len(), || single_pass(scene, rays));
    let (batch, batch_hits) = time_pass(&pool, rays.len(), || batch_pass(scene, rays));
    if raw_hits != single_hits || raw_hits != batch_hits {
        return Err(Error::Embree {
            code: 0,
            message: format!(
                "ray paths disagree: raw {raw_hits} hits, single {single_hits}, batch {batch_hits} \
                 of {} rays",
                rays.len()
            ),
        });
    }
    Ok(Throughput {
        raw_mrays_per_s: raw,
        single_mrays_per_s: single,
        batch_mrays_per_s: batch,
        threads: pool.current_num_threads(),
        rays: rays.len(),
        hits: raw_hits,
    })
}
