//! Images and irradiance from the path tracer ([`super::path`]), and its own
//! noise measured from two independent halves.
//!
//! **Noise of a mean of two halves.** With `A` and `B` two renders of
//! independent seeds and the same expectation, `A - B` has twice the variance
//! of one half and `(A + B) / 2` half of it, so the rms noise of the mean is
//! `rmse(A, B) / 2`. Divided by the mean's mean it is the relative noise the
//! trade study compares with the errors it judges.

use super::camera::CameraRays;
use super::path::{PathPart, PathTracer};
use super::run::{pixel_mean, RenderStats};
use super::{Image, RenderConfig};
use crate::embree::{CommittedScene, Ray};
use crate::error::Result;
use crate::rng::{hash2, Rng};
use crate::sampling::{cosine_hemisphere, Frame};
use crate::scene::{Scene, SurfacePoint};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::f32::consts::PI;
use std::sync::atomic::{AtomicU64, Ordering};

/// Renders `part` of the light of `scene` with the path tracer, on the
/// current rayon pool. Reads `width`, `height`, `rows` (a tile), `spp`,
/// `seed`, `camera` and `show_emitters` of `cfg` (no photon-map settings).
/// `progress(rows_done, rows_total)` is called from worker threads.
///
/// # Errors
/// [`crate::Error::InvalidParameter`] for bad settings,
/// [`crate::Error::InvalidScene`] for a scene that fails
/// [`Scene::validate`].
pub fn render_path(
    scene: &Scene,
    rt: &CommittedScene,
    cfg: &RenderConfig,
    part: PathPart,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<Image> {
    render_path_with(scene, rt, cfg, part, progress).map(|(image, _)| image)
}

/// [`render_path`] with the render's counts ([`RenderStats::samples`] and
/// [`RenderStats::dropped_samples`]; the photon-map fields are 0).
///
/// # Errors
/// As [`render_path`].
pub fn render_path_with(
    scene: &Scene,
    rt: &CommittedScene,
    cfg: &RenderConfig,
    part: PathPart,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(Image, RenderStats)> {
    cfg.validate()?;
    scene.validate()?;
    // A tile is an image of its rows only; pixels keep their whole-image
    // index, so their samples are the whole image's.
    let (y0, y1) = cfg.rows.unwrap_or((0, cfg.height));
    let mut image = Image::new(cfg.width, y1 - y0)?;
    let rays = CameraRays::new(&cfg.camera_for(scene)?, cfg.width, cfg.height);
    let pt = PathTracer::new(scene, rt);
    let width = cfg.width as usize;
    let rows = (y1 - y0) as u64;
    let done = AtomicU64::new(0);
    let dropped = AtomicU64::new(0);
    image
        .pixels
        .par_chunks_mut(width)
        .enumerate()
        .for_each(|(y, row)| {
            let y = y + y0 as usize;
            let mut row_dropped = 0;
            for (x, px) in row.iter_mut().enumerate() {
                let key = hash2(cfg.seed, (y * width + x) as u64);
                let (mut sum, mut kept) = (DVec3::ZERO, 0);
                for s in 0..cfg.spp {
                    let mut rng = Rng::new(hash2(key, s as u64));
                    let [jx, jy] = rng.next_2d();
                    let ray = rays.ray(x as f32 + jx, y as f32 + jy);
                    let l = pt.radiance(ray, part, cfg.show_emitters, &mut rng);
                    // A NaN or infinite sample is dropped, not spread, and counted.
                    if l.is_finite() {
                        sum += l.as_dvec3();
                        kept += 1;
                    }
                }
                let (mean, dropped_here) = pixel_mean(sum, kept, cfg.spp);
                *px = mean;
                row_dropped += dropped_here;
            }
            dropped.fetch_add(row_dropped, Ordering::Relaxed);
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, rows);
        });
    let stats = RenderStats {
        samples: cfg.width as u64 * rows * cfg.spp as u64,
        dropped_samples: dropped.into_inner(),
        ..RenderStats::default()
    };
    Ok((image, stats))
}

/// A path-traced image as two independent halves.
#[derive(Clone, Debug)]
pub struct PathHalves {
    /// Half A (seed `cfg.seed`).
    pub a: Image,
    /// Half B (an independent seed).
    pub b: Image,
    /// Samples of both halves left out as NaN or infinite
    /// ([`RenderStats::dropped_samples`]).
    pub dropped_samples: u64,
}

impl PathHalves {
    /// Renders both halves, each with `cfg.spp` samples per pixel.
    ///
    /// # Errors
    /// As [`render_path`].
    pub fn render(
        scene: &Scene,
        rt: &CommittedScene,
        cfg: &RenderConfig,
        part: PathPart,
    ) -> Result<Self> {
        let (a, sa) = render_path_with(scene, rt, cfg, part, &|_, _| {})?;
        let mut cb = cfg.clone();
        cb.seed = hash2(cfg.seed, 0x0B_5EED);
        let (b, sb) = render_path_with(scene, rt, &cb, part, &|_, _| {})?;
        Ok(PathHalves {
            a,
            b,
            dropped_samples: sa.dropped_samples + sb.dropped_samples,
        })
    }

    /// Refuses halves that left samples out: as a reference they would bias
    /// every error measured against them.
    ///
    /// # Errors
    /// [`crate::Error::InvalidScene`] naming the count.
    pub fn require_complete(&self) -> Result<()> {
        if self.dropped_samples > 0 {
            return Err(crate::Error::InvalidScene(format!(
                "the path-traced reference left out {} NaN or infinite samples \
                 (degenerate geometry, or radiance beyond f32)",
                self.dropped_samples
            )));
        }
        Ok(())
    }

    /// The mean of the halves.
    pub fn mean(&self) -> Image {
        let mut m = self.a.clone();
        for (p, q) in m.pixels.iter_mut().zip(&self.b.pixels) {
            *p = (*p + *q) * 0.5;
        }
        m
    }

    /// Relative rms noise of [`PathHalves::mean`] over the pixels where
    /// `keep` is true (all when `None`): `rmse(A, B) / 2 / mean`.
    pub fn noise_rel(&self, keep: Option<&[bool]>) -> f64 {
        let (mut se, mut sum, mut n) = (0.0f64, 0.0f64, 0usize);
        for (i, (p, q)) in self.a.pixels.iter().zip(&self.b.pixels).enumerate() {
            if keep.is_some_and(|k| !k.get(i).copied().unwrap_or(false)) {
                continue;
            }
            se += (*p - *q).as_dvec3().length_squared();
            sum += (*p + *q).as_dvec3().element_sum() * 0.5;
            n += 3;
        }
        if n == 0 || sum <= 0.0 {
            return 0.0;
        }
        (se / n as f64).sqrt() / 2.0 / (sum / n as f64)
    }
}

/// For each pixel, whether the ray through its centre first hits an emitter
/// (a light's own pixel, excluded from the trade study's image errors).
///
/// # Errors
/// [`crate::Error::InvalidScene`] when neither `cfg` nor the scene has a camera.
pub fn light_pixels(scene: &Scene, rt: &CommittedScene, cfg: &RenderConfig) -> Result<Vec<bool>> {
    let rays = CameraRays::new(&cfg.camera_for(scene)?, cfg.width, cfg.height);
    let w = cfg.width as usize;
    Ok((0..w * cfg.height as usize)
        .map(|i| {
            let ray = rays.ray((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            rt.intersect(&ray).is_some_and(|h| {
                scene
                    .materials
                    .get(h.material as usize)
                    .is_some_and(|m| m.emission.is_some())
            })
        })
        .collect())
}

/// For each pixel, whether the ray through its centre first hits a specular
/// surface (a mirror or glass): not a caustic's pixel, whatever the image
/// shows there.
///
/// # Errors
/// [`crate::Error::InvalidScene`] when neither `cfg` nor the scene has a camera.
pub fn specular_pixels(
    scene: &Scene,
    rt: &CommittedScene,
    cfg: &RenderConfig,
) -> Result<Vec<bool>> {
    let rays = CameraRays::new(&cfg.camera_for(scene)?, cfg.width, cfg.height);
    let w = cfg.width as usize;
    Ok((0..w * cfg.height as usize)
        .map(|i| {
            let ray = rays.ray((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            rt.intersect(&ray).is_some_and(|h| {
                scene
                    .materials
                    .get(h.material as usize)
                    .is_some_and(|m| m.brdf.is_specular())
            })
        })
        .collect())
}

/// Irradiance arriving at each point (on the side of its normal) that is
/// *not* direct light: light that left some surface (caustics included), by
/// `samples` cosine-distributed path-traced rays per point. `E_indirect =
/// pi * mean(L)` for cosine-weighted directions. Adding the direct light's
/// quadrature ([`super::quadrature_irradiance`]) gives the full irradiance.
/// Point `i` draws from `hash2(seed, i)`; points run in parallel.
pub fn indirect_irradiance(
    scene: &Scene,
    rt: &CommittedScene,
    points: &[SurfacePoint],
    samples: u32,
    seed: u64,
) -> Vec<Vec3> {
    let pt = PathTracer::new(scene, rt);
    let samples = samples.max(1);
    points
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let frame = Frame::from_normal(p.normal);
            let origin = p.position + p.normal * pt.eps;
            let key = hash2(seed, i as u64);
            let mut sum = Vec3::ZERO;
            for s in 0..samples {
                let mut rng = Rng::new(hash2(key, s as u64));
                let dir = frame.world_from_local(cosine_hemisphere(rng.next_2d()));
                let l = pt.radiance_after_first_bounce(Ray::new(origin, dir), &mut rng);
                if l.is_finite() {
                    sum += l;
                }
            }
            sum * (PI / samples as f32)
        })
        .collect()
}
