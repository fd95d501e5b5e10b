//! Running the estimator over an image: rows of pixels in parallel, the
//! cache built first when the settings ask for one, the [`RenderStats`].

use super::cache::{CacheConfig, IrradianceCache};
use super::camera::CameraRays;
use super::direct::LightSampler;
use super::estimate::Lookup;
use super::integrator::{Ctx, Scratch};
use super::sampler::{dim, PixelSampler};
use super::CAUSTIC_RADIUS_FRACTION;
use super::{default_max_radius, ray_epsilon, Image, RenderConfig, RenderMaps, View};
use crate::embree::CommittedScene;
use crate::engine::albedo::AlbedoTable;
use crate::error::{Error, Result};
use crate::rng::{hash2, Rng};
use crate::scene::Scene;
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// What a render measured besides its image.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Camera samples taken.
    pub samples: u64,
    /// Seconds spent in photon-map and cache lookups, summed over threads
    /// (one lookup in 16 is timed and counted 16 times).
    pub lookup_s: f64,
    /// Lookups answered by the cache.
    pub cache_hits: u64,
    /// Lookups that fell back to the k-nearest estimate.
    pub cache_misses: u64,
    /// Seconds to build the irradiance cache (0 when none was built here).
    pub cache_build_s: f64,
    /// Entries of the cache read (0 without one).
    pub cache_entries: usize,
    /// Bytes per cache entry (0 without one).
    pub cache_bytes_per_entry: usize,
    /// Camera samples whose radiance was NaN or infinite (degenerate
    /// geometry, or a light so close its `I / r^2` overflows f32), left
    /// out of their pixel's mean. Not 0: the image is biased there; the
    /// command line warns.
    pub dropped_samples: u64,
}

/// Renders `scene` (whose Embree geometry is `rt`) with `maps`, on the current
/// rayon pool. `progress(rows_done, rows_total)` is called from worker threads.
///
/// # Errors
/// [`Error::InvalidParameter`] for bad settings or a view that needs a photon
/// map when `maps` is `None`.
pub fn render(
    scene: &Scene,
    rt: &CommittedScene,
    maps: Option<&RenderMaps>,
    cfg: &RenderConfig,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<Image> {
    render_with(scene, rt, maps, None, cfg, progress).map(|(image, _)| image)
}

/// [`render`] returning the render's [`RenderStats`]. The gather reads its
/// hits from `cache` when given; else, when the settings ask for a cache
/// (`cache_stride > 0`, a gather, the full view), one is built from
/// `maps.full` first (its time is in [`RenderStats::cache_build_s`]).
///
/// # Errors
/// As [`render`].
pub fn render_with(
    scene: &Scene,
    rt: &CommittedScene,
    maps: Option<&RenderMaps>,
    cache: Option<&IrradianceCache>,
    cfg: &RenderConfig,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(Image, RenderStats)> {
    cfg.validate()?;
    scene.validate()?;
    if maps.is_none() && cfg.view != View::DirectOnly {
        return Err(Error::param(
            "photon map",
            "this view reads the photon map; pass one or use the direct-only view",
        ));
    }
    if cfg.reads_split_maps() && maps.is_some_and(|m| m.is_full_only()) {
        return Err(Error::param(
            "photon map",
            "these settings read the primary or indirect map, but the maps were built \
             full-only (Maps::full_only); build them with Maps::from_photons",
        ));
    }
    // A tile (`cfg.rows`) is an image of its rows only; pixels keep their
    // whole-image index, so their samples are the whole image's.
    let (y0, y1) = cfg.rows.unwrap_or((0, cfg.height));
    let mut image = Image::new(cfg.width, y1 - y0)?;
    let max_radius = cfg.max_radius.unwrap_or_else(|| default_max_radius(scene));
    let lookup = Lookup {
        k: cfg.k,
        max_radius,
    };
    let built = match (cache, maps) {
        (None, Some(m))
            if cfg.cache_stride > 0 && cfg.final_gather > 0 && cfg.view == View::Full =>
        {
            let (lo, hi) = scene.bounds();
            let c = CacheConfig {
                stride: cfg.cache_stride,
                lookup,
            };
            Some(IrradianceCache::build(&m.full, rt, (hi - lo).length(), &c)?)
        }
        _ => None,
    };
    let cache = cache.or(built.as_ref());
    let camera = cfg.camera_for(scene)?;
    let rays = CameraRays::new(&camera, cfg.width, cfg.height);
    let ctx = Ctx {
        scene,
        rt,
        maps,
        cache,
        lights: LightSampler::new(scene),
        albedo: match cache {
            Some(_) => scene
                .materials()
                .iter()
                .map(|m| AlbedoTable::new(&m.brdf))
                .collect(),
            None => Vec::new(),
        },
        view: cfg.view,
        gather: cfg.final_gather,
        light_samples: cfg.light_samples,
        spp: cfg.spp,
        lookup,
        caustic_lookup: Lookup {
            k: cfg.caustic_k,
            max_radius: cfg
                .caustic_max_radius
                .unwrap_or(max_radius * CAUSTIC_RADIUS_FRACTION),
        },
        eps: ray_epsilon(scene),
        show_emitters: cfg.show_emitters,
    };
    let width = cfg.width as usize;
    let rows = (y1 - y0) as u64;
    let done = AtomicU64::new(0);
    let (lookup_ns, hits, misses) = (AtomicU64::new(0), AtomicU64::new(0), AtomicU64::new(0));
    let dropped = AtomicU64::new(0);
    image
        .pixels
        .par_chunks_mut(width)
        .enumerate()
        .for_each(|(y, row)| {
            let y = y + y0 as usize;
            let mut sc = Scratch::new(cfg.k);
            let mut row_dropped = 0;
            for (x, px) in row.iter_mut().enumerate() {
                let pixel = (y * width + x) as u64;
                let key = hash2(cfg.seed, pixel);
                let sampler = PixelSampler::new(key);
                let mut sum = DVec3::ZERO;
                let mut kept = 0;
                for s in 0..cfg.spp {
                    let mut rng = Rng::new(hash2(key, s as u64));
                    let [jx, jy] = sampler.get_2d(dim::PIXEL, s, cfg.spp);
                    let ray = rays.ray(x as f32 + jx, y as f32 + jy);
                    let l = ctx.radiance(ray, (&sampler, s), &mut rng, &mut sc);
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
            lookup_ns.fetch_add(sc.lookup_ns, Ordering::Relaxed);
            hits.fetch_add(sc.hits, Ordering::Relaxed);
            misses.fetch_add(sc.misses, Ordering::Relaxed);
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, rows);
        });
    let stats = RenderStats {
        samples: cfg.width as u64 * rows * cfg.spp as u64,
        lookup_s: lookup_ns.into_inner() as f64 * 1e-9,
        cache_hits: hits.into_inner(),
        cache_misses: misses.into_inner(),
        cache_build_s: built.as_ref().map_or(0.0, |c| c.build_s),
        cache_entries: cache.map_or(0, |c| c.len()),
        cache_bytes_per_entry: cache.map_or(0, |c| c.bytes_per_entry()),
        dropped_samples: dropped.into_inner(),
    };
    Ok((image, stats))
}

/// A pixel from the f64 sum of its `kept` finite samples out of `spp`, and
/// how many of its samples were dropped (summed in f32, samples near f32's
/// range overflowed to infinite pixels). A mean beyond f32 drops them all.
pub(crate) fn pixel_mean(sum: DVec3, kept: u32, spp: u32) -> (Vec3, u64) {
    let mean = (sum / f64::from(spp)).as_vec3();
    if mean.is_finite() {
        (mean, u64::from(spp - kept))
    } else {
        (Vec3::ZERO, u64::from(spp))
    }
}
