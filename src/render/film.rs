//! The image loop, written once for every estimator (as pbrt-v4's
//! `ImageTileIntegrator::Render` is): the rows of a tile in parallel, each
//! pixel's key, its samples' random streams, their f64 sum, and the samples
//! dropped as NaN or infinite. An estimator supplies only the radiance of
//! one sample ([`PixelEstimator`]), or of a pixel's samples
//! [`SAMPLES_PER_BATCH`] at a time, when it casts their rays in batches.
//!
//! Pixel `p` (its whole-image index, also inside a tile) has the key
//! `hash2(seed, p)`; its sample `s` draws from `Rng::new(hash2(key, s))`. So an
//! image does not depend on the thread count or the tiling.

use super::camera::CameraRays;
use super::{CheckedRender, Image};
use crate::error::Result;
use crate::raycast::Ray;
use crate::rng::{hash2, Rng};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// One camera sample's place: its pixel and its index among the pixel's
/// samples.
#[derive(Clone, Copy, Debug)]
pub(super) struct Sample {
    /// Column.
    pub x: u32,
    /// Row, in the whole image.
    pub y: u32,
    /// Index among the pixel's `spp` samples.
    pub s: u32,
}

/// The radiance of one camera sample, for [`develop`].
pub(super) trait PixelEstimator: Sync {
    /// A row's scratch space and counters, handed back to
    /// [`PixelEstimator::row_done`].
    type Row: Send;
    /// What a pixel's samples share, made from its key.
    type Pixel;

    /// Fresh scratch space for a row.
    fn row(&self) -> Self::Row;

    /// The state a pixel's samples share, from its key and its place
    /// `(x, y)` in the whole image.
    fn pixel(&self, key: u64, x: u32, y: u32) -> Self::Pixel;

    /// One sample of the radiance arriving at the camera through `sample`.
    fn radiance(
        &self,
        rays: &CameraRays,
        pixel: &Self::Pixel,
        sample: Sample,
        rng: &mut Rng,
        row: &mut Self::Row,
    ) -> Vec3;

    /// The radiance of `samples` (of one pixel, in order), each drawing
    /// from its own stream in `rngs`, into `out`: what one
    /// [`PixelEstimator::radiance`] per sample gives, which is the default.
    /// An estimator overrides it to send the samples' rays to the caster in
    /// batches.
    fn radiance_batch(
        &self,
        rays: &CameraRays,
        pixel: &Self::Pixel,
        samples: &[Sample],
        rngs: &mut [Rng],
        row: &mut Self::Row,
        out: &mut [Vec3],
    ) {
        one_by_one(self, rays, pixel, samples, rngs, row, out);
    }

    /// A row is finished; its counters are final.
    fn row_done(&self, row: Self::Row);
}

/// [`PixelEstimator::radiance_batch`] as one [`PixelEstimator::radiance`]
/// per sample: the default, and the fallback of an estimator that batches
/// only some renders.
pub(super) fn one_by_one<E: PixelEstimator + ?Sized>(
    estimator: &E,
    rays: &CameraRays,
    pixel: &E::Pixel,
    samples: &[Sample],
    rngs: &mut [Rng],
    row: &mut E::Row,
    out: &mut [Vec3],
) {
    for ((&sample, rng), l) in samples.iter().zip(rngs).zip(out) {
        *l = estimator.radiance(rays, pixel, sample, rng, row);
    }
}

/// Samples of a pixel handed to [`PixelEstimator::radiance_batch`] at a
/// time: a packet of camera rays as wide as AVX-512's.
pub(super) const SAMPLES_PER_BATCH: u32 = 16;

/// The jittered camera ray through `sample`'s pixel, from the point `jitter`
/// in `[0, 1)^2`.
pub(super) fn camera_ray(rays: &CameraRays, sample: Sample, [jx, jy]: [f32; 2]) -> Ray {
    rays.ray(sample.x as f32 + jx, sample.y as f32 + jy)
}

/// Renders the rows `cfg.rows` (all when `None`) of the image `cfg`
/// describes with `estimator`, on the current rayon pool, calling
/// `progress(rows_done, rows_total)` from worker threads. Returns the image
/// and the number of samples dropped as NaN or infinite.
///
/// # Errors
/// What [`Image::new`] refuses (memory the system will not give).
pub(super) fn develop<E: PixelEstimator>(
    cfg: &CheckedRender,
    rays: &CameraRays,
    estimator: &E,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(Image, u64)> {
    // A tile is an image of its rows only; pixels keep their whole-image
    // index, so their samples are the whole image's.
    let (y0, y1) = cfg.rows.unwrap_or((0, cfg.height));
    let mut image = Image::new(cfg.width, y1 - y0)?;
    let width = cfg.width as usize;
    let rows = u64::from(y1 - y0);
    let done = AtomicU64::new(0);
    let dropped = AtomicU64::new(0);
    image
        .pixels
        .par_chunks_mut(width)
        // A row a task: rayon otherwise splits the rows only down to a
        // few runs per thread and runs each to its end, so the last run
        // on one thread left the other idle for a fifth of a render.
        .with_max_len(1)
        .enumerate()
        .for_each(|(row_index, pixels)| {
            let y = row_index as u32 + y0;
            let mut row = estimator.row();
            let mut row_dropped = 0;
            for (x, px) in pixels.iter_mut().enumerate() {
                let key = hash2(cfg.seed, y as u64 * width as u64 + x as u64);
                let pixel = estimator.pixel(key, x as u32, y);
                let mut sum = DVec3::ZERO;
                let mut kept = 0;
                for first in (0..cfg.spp).step_by(SAMPLES_PER_BATCH as usize) {
                    let n = SAMPLES_PER_BATCH.min(cfg.spp - first) as usize;
                    let samples: [Sample; SAMPLES_PER_BATCH as usize] =
                        std::array::from_fn(|k| Sample {
                            x: x as u32,
                            y,
                            s: first + k as u32,
                        });
                    let mut rngs = samples.map(|s| Rng::new(hash2(key, u64::from(s.s))));
                    let mut out = [Vec3::ZERO; SAMPLES_PER_BATCH as usize];
                    estimator.radiance_batch(
                        rays,
                        &pixel,
                        &samples[..n],
                        &mut rngs[..n],
                        &mut row,
                        &mut out[..n],
                    );
                    // A NaN or infinite sample is dropped, not spread, and counted.
                    for l in out[..n].iter().filter(|l| l.is_finite()) {
                        sum += l.as_dvec3();
                        kept += 1;
                    }
                }
                let (mean, dropped_here) = pixel_mean(sum, kept, cfg.spp);
                *px = mean;
                row_dropped += dropped_here;
            }
            dropped.fetch_add(row_dropped, Ordering::Relaxed);
            estimator.row_done(row);
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, rows);
        });
    Ok((image, dropped.into_inner()))
}

/// A pixel from the f64 sum of its `kept` finite samples out of `spp`, and
/// how many of its samples were dropped (summed in f32, samples near f32's
/// range overflowed to infinite pixels). A mean beyond f32 drops them all.
fn pixel_mean(sum: DVec3, kept: u32, spp: u32) -> (Vec3, u64) {
    let mean = (sum / f64::from(spp)).as_vec3();
    if mean.is_finite() {
        (mean, u64::from(spp - kept))
    } else {
        (Vec3::ZERO, u64::from(spp))
    }
}
