//! The photon render: its settings checked, the cache built first when they
//! ask for one, the estimator run over the image ([`super::film`]), the
//! [`RenderStats`].

use super::cache::{CacheConfig, IrradianceCache};
use super::camera::CameraRays;
use super::direct::LightSampler;
use super::estimate::Lookup;
use super::film::{self, PixelEstimator, Sample};
use super::gather_plan::{self, GatherDirections, GatherPlan};
use super::integrator::{Ctx, SampleScratch};
use super::path_render::light_pixels;
use super::progressive::{render_to_noise, NoiseTarget, Progressive, Round};
use super::reads::MapReads;
use super::sampler::{dim, PixelSampler};
use super::CAUSTIC_RADIUS_FRACTION;
use super::{
    default_max_radius, ray_epsilon, CheckedRender, Image, RenderConfig, RenderMaps, View,
};
use crate::engine::albedo::AlbedoTable;
use crate::error::{Error, Result};
use crate::raycast::{CheckedCaster, Ray, RayCaster};
use crate::rng::Rng;
use crate::scene::{PreparedScene, Scene};
use glam::Vec3;
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
    /// Entries that a wall crosses, read only by lookups that see their
    /// representative point (0 without a cache).
    pub cache_walled: usize,
    /// Cells holding a gather guide, and the bytes of their table (0
    /// without a cache).
    pub cache_guides: (usize, usize),
    /// Camera samples whose radiance was NaN or infinite (degenerate
    /// geometry, or a light so close its `I / r^2` overflows f32), left
    /// out of their pixel's mean. Not 0: the image is biased there; the
    /// command line warns.
    pub dropped_samples: u64,
    /// Seconds of the gather plan's pilot (0 without a plan:
    /// [`GatherAllocation`](super::GatherAllocation)).
    pub gather_plan_s: f64,
    /// Mean final-gather rays per camera sample over the image's pixels.
    pub mean_gather: f64,
}

/// Renders the scene of `prepared` with `maps`, on the current rayon pool,
/// over whatever [`RayCaster`] it was prepared with (Embree's, or a
/// renderer's own).
///
/// # Errors
/// [`Error::InvalidParameter`] for bad settings or a view that needs a photon
/// map when `maps` is `None`.
pub fn render<C: RayCaster>(
    prepared: &PreparedScene<C>,
    maps: Option<&RenderMaps>,
    cfg: &RenderConfig,
) -> Result<Image> {
    render_with(prepared, maps, None, cfg, &|_, _| {}).map(|(image, _)| image)
}

/// [`render`] with a progress callback, `progress(rows_done, rows_total)`,
/// called from worker threads, returning the render's [`RenderStats`]. The gather reads its
/// hits from `cache` when given; else, when the settings ask for a cache
/// (`cache_stride > 0`, a gather, the full view), one is built from
/// `maps.full` first (its time is in [`RenderStats::cache_build_s`]).
///
/// # Errors
/// As [`render`].
pub fn render_with<C: RayCaster>(
    prepared: &PreparedScene<C>,
    maps: Option<&RenderMaps>,
    cache: Option<&IrradianceCache>,
    cfg: &RenderConfig,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(Image, RenderStats)> {
    render_checked(prepared, maps, cache, &cfg.check()?, progress)
}

/// [`render_with`] for settings checked already ([`RenderConfig::check`]):
/// a program that checks its settings before any work renders with them
/// as they are.
///
/// # Errors
/// As [`render`], but for the settings.
pub fn render_checked<C: RayCaster>(
    prepared: &PreparedScene<C>,
    maps: Option<&RenderMaps>,
    cache: Option<&IrradianceCache>,
    cfg: &CheckedRender,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(Image, RenderStats)> {
    let (scene, rt) = (prepared.scene(), prepared.caster());
    render_photons(scene, rt, (maps, cache, None), cfg, progress, None)
}

/// [`render_with`] (without a cache given: it builds its own when the
/// settings ask for one) that marks every photon its lookups return in
/// `reads`, for [`MapReads::share`]; the image is [`render`]'s, bit for
/// bit. Slower than a plain render by the marking (see [`super::reads`]).
///
/// # Errors
/// As [`render`].
pub fn render_reading<C: RayCaster>(
    prepared: &PreparedScene<C>,
    reads: &MapReads,
    cfg: &RenderConfig,
) -> Result<(Image, RenderStats)> {
    let (scene, rt) = (prepared.scene(), prepared.caster());
    let maps = Some(reads.maps());
    render_photons(
        scene,
        rt,
        (maps, None, None),
        &cfg.check()?,
        &|_, _| {},
        Some(reads),
    )
}

/// The irradiance cache the settings ask for (`cache_stride > 0`, a gather,
/// the full view), built from `maps.full`; `None` when they ask for none.
fn cache_for(
    scene: &Scene,
    rt: &dyn RayCaster,
    maps: Option<&RenderMaps>,
    cfg: &CheckedRender,
    reads: Option<&MapReads>,
) -> Result<Option<IrradianceCache>> {
    match maps {
        Some(m) if cfg.cache_stride > 0 && cfg.final_gather > 0 && cfg.view == View::Full => {
            let c = CacheConfig {
                stride: cfg.cache_stride,
                lookup: lookup_of(scene, cfg),
            };
            Ok(Some(IrradianceCache::build_in(
                &m.full, scene, rt, &c, reads,
            )?))
        }
        _ => Ok(None),
    }
}

fn lookup_of(scene: &Scene, cfg: &CheckedRender) -> Lookup {
    Lookup {
        k: cfg.k,
        max_radius: cfg.max_radius.unwrap_or_else(|| default_max_radius(scene)),
    }
}

/// [`render_checked`] in rounds of two independent halves until the image's
/// own noise over the pixels that are not a light's reaches `target`
/// ([`super::progressive`]). The irradiance cache, when the settings ask for
/// one, is built once and read by every round; `progress(rows_done,
/// rows_total)` follows each half-round's rows, `on_round` each round. The
/// stats sum every round's.
///
/// # Errors
/// As [`render`], and for a bad `target`.
pub fn render_progressive<C: RayCaster>(
    prepared: &PreparedScene<C>,
    maps: Option<&RenderMaps>,
    cfg: &CheckedRender,
    target: &NoiseTarget,
    progress: &(dyn Fn(u64, u64) + Sync),
    on_round: &mut dyn FnMut(&Round),
) -> Result<(Progressive, RenderStats)> {
    target.validate()?;
    let (scene, rt) = (prepared.scene(), prepared.caster());
    check_maps(cfg, maps)?;
    let cache = cache_for(scene, rt, maps, cfg, None)?;
    // One plan for every round: its pilot is the settings', not a half's.
    let plan = gather_plan_for(scene, rt, maps, cache.as_ref(), cfg)?;
    let mut stats = RenderStats::default();
    let mut half = |c: &CheckedRender| {
        let sources = (maps, cache.as_ref(), plan.as_ref());
        let (image, s) = render_photons(scene, rt, sources, c, progress, None)?;
        stats.add(&s);
        Ok(image)
    };
    let p = render_halves_to_noise(prepared, cfg, target, &mut half, on_round)?;
    if let Some(c) = &cache {
        stats.cache_build_s = c.build_s;
    }
    if let Some(p) = &plan {
        stats.gather_plan_s = p.seconds;
    }
    Ok((p, stats))
}

/// The rounds of [`render_to_noise`] for any renderer of half images
/// (`half(cfg)`: `cfg.spp` samples with `cfg.seed`), over the pixels that
/// are not a light's, the halves rendered with the emitters hidden and the
/// emission the camera sees added after them (when `cfg.show_emitters`).
///
/// # Errors
/// A bad `target`; whatever `half` returns.
pub fn render_halves_to_noise<C: RayCaster>(
    prepared: &PreparedScene<C>,
    cfg: &CheckedRender,
    target: &NoiseTarget,
    half: &mut dyn FnMut(&CheckedRender) -> Result<Image>,
    on_round: &mut dyn FnMut(&Round),
) -> Result<Progressive> {
    let keep: Vec<bool> = light_pixels(prepared, cfg)?.iter().map(|l| !l).collect();
    let mut p = render_to_noise(&cfg.without_emitters(), target, &keep, half, on_round)?;
    add_seen_emission(prepared, cfg, p.spp, &mut p.image)?;
    Ok(p)
}

/// When `cfg.show_emitters`, adds to `image` (rendered with the emitters
/// hidden) the emission the camera sees, [`View::Emitters`] at `spp`
/// samples per pixel: the light's edges anti-aliased, kept out of a noise
/// estimate they would dominate.
fn add_seen_emission<C: RayCaster>(
    prepared: &PreparedScene<C>,
    cfg: &CheckedRender,
    spp: u32,
    image: &mut Image,
) -> Result<()> {
    if !cfg.show_emitters {
        return Ok(());
    }
    let mut c: RenderConfig = (**cfg).clone();
    c.view = View::Emitters;
    c.spp = spp;
    c.seed = crate::rng::hash2(cfg.seed, 0xE417);
    let (seen, _) = render_checked(prepared, None, None, &c.check()?, &|_, _| {})?;
    if seen.pixels.len() != image.pixels.len() {
        return Err(Error::param(
            "image",
            "the emission's size differs from the image's",
        ));
    }
    for (p, e) in image.pixels.iter_mut().zip(&seen.pixels) {
        *p += *e;
    }
    Ok(())
}

fn check_maps(cfg: &RenderConfig, maps: Option<&RenderMaps>) -> Result<()> {
    if maps.is_none() && !matches!(cfg.view, View::DirectOnly | View::Emitters) {
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
    Ok(())
}

/// What a render reads besides its settings: the maps, an irradiance cache
/// built already, a gather plan made already (each built here when the
/// settings ask for it and none is given).
type Sources<'a> = (
    Option<&'a RenderMaps>,
    Option<&'a IrradianceCache>,
    Option<&'a GatherPlan>,
);

// One body for every caster (behind `dyn`: a virtual call is nothing next
// to a ray and a photon lookup), so the renderer is compiled once.
fn render_photons(
    scene: &Scene,
    rt: &dyn RayCaster,
    (maps, cache, plan): Sources<'_>,
    cfg: &CheckedRender,
    progress: &(dyn Fn(u64, u64) + Sync),
    reads: Option<&MapReads>,
) -> Result<(Image, RenderStats)> {
    check_maps(cfg, maps)?;
    let checked = CheckedCaster::new(scene, rt);
    let rt: &dyn RayCaster = &checked;
    let built = match cache {
        None => cache_for(scene, rt, maps, cfg, reads)?,
        Some(_) => None,
    };
    let cache = cache.or(built.as_ref());
    let rays = CameraRays::new(&cfg.camera_for(scene)?, cfg.width, cfg.height);
    let ctx = context(scene, rt, (maps, cache), cfg, reads);
    let planned = match (plan, maps) {
        (None, Some(m)) => gather_plan::plan(&ctx, m, &rays, cfg),
        _ => None,
    };
    let plan = plan.or(planned.as_ref());
    let estimator = PhotonEstimator {
        ctx,
        k: cfg.k,
        plan,
        lookup_ns: AtomicU64::new(0),
        hits: AtomicU64::new(0),
        misses: AtomicU64::new(0),
    };
    let (image, dropped) = film::develop(cfg, &rays, &estimator, progress)?;
    checked.result()?;
    let stats = RenderStats {
        samples: u64::from(image.width) * u64::from(image.height) * u64::from(cfg.spp),
        lookup_s: estimator.lookup_ns.into_inner() as f64 * 1e-9,
        cache_hits: estimator.hits.into_inner(),
        cache_misses: estimator.misses.into_inner(),
        cache_build_s: built.as_ref().map_or(0.0, |c| c.build_s),
        cache_entries: cache.map_or(0, |c| c.len()),
        cache_bytes_per_entry: cache.map_or(0, |c| c.bytes_per_entry()),
        cache_walled: cache.map_or(0, |c| c.walled()),
        cache_guides: cache.map_or((0, 0), |c| (c.guides(), c.guide_bytes())),
        dropped_samples: dropped,
        gather_plan_s: planned.as_ref().map_or(0.0, |p| p.seconds),
        mean_gather: plan.map_or(f64::from(estimator.ctx.gather), GatherPlan::mean),
    };
    Ok((image, stats))
}

/// The per-sample estimator of `cfg` over `rt`, reading `maps` and `cache`.
fn context<'a>(
    scene: &'a Scene,
    rt: &'a dyn RayCaster,
    (maps, cache): (Option<&'a RenderMaps>, Option<&'a IrradianceCache>),
    cfg: &CheckedRender,
    reads: Option<&'a MapReads<'a>>,
) -> Ctx<'a> {
    let lookup = lookup_of(scene, cfg);
    Ctx {
        scene,
        rt,
        maps,
        cache,
        lights: LightSampler::over(scene, rt),
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
                .unwrap_or(lookup.max_radius * CAUSTIC_RADIUS_FRACTION),
        },
        eps: ray_epsilon(scene),
        show_emitters: cfg.show_emitters,
        reads,
        guided: cfg.gather_directions == GatherDirections::Guided,
    }
}

/// The gather plan `cfg` asks for ([`gather_plan`]), reading `maps` and
/// `cache`; `None` when it asks for none.
fn gather_plan_for(
    scene: &Scene,
    rt: &dyn RayCaster,
    maps: Option<&RenderMaps>,
    cache: Option<&IrradianceCache>,
    cfg: &CheckedRender,
) -> Result<Option<GatherPlan>> {
    let Some(m) = maps else { return Ok(None) };
    let checked = CheckedCaster::new(scene, rt);
    let ctx = context(scene, &checked, (maps, cache), cfg, None);
    let rays = CameraRays::new(&cfg.camera_for(scene)?, cfg.width, cfg.height);
    let plan = gather_plan::plan(&ctx, m, &rays, cfg);
    checked.result()?;
    Ok(plan)
}

impl RenderStats {
    /// Adds another render's counts and times (the cache's size and build
    /// time are one cache's: taken from `other` when this has none).
    fn add(&mut self, other: &RenderStats) {
        self.samples += other.samples;
        self.lookup_s += other.lookup_s;
        self.cache_hits += other.cache_hits;
        self.cache_misses += other.cache_misses;
        self.dropped_samples += other.dropped_samples;
        if self.cache_entries == 0 {
            self.cache_entries = other.cache_entries;
            self.cache_bytes_per_entry = other.cache_bytes_per_entry;
            self.cache_walled = other.cache_walled;
            self.cache_guides = other.cache_guides;
        }
    }
}

/// The photon render's estimator ([`Ctx::radiance`]) in the image loop, with
/// the lookup counters of its rows.
struct PhotonEstimator<'a> {
    ctx: Ctx<'a>,
    k: usize,
    /// Gather rays per pixel; `None`: `ctx.gather` in every pixel.
    plan: Option<&'a GatherPlan>,
    lookup_ns: AtomicU64,
    hits: AtomicU64,
    misses: AtomicU64,
}

impl PhotonEstimator<'_> {
    /// The camera ray of `sample`, jittered by the pixel's stratified point.
    fn camera_ray(&self, rays: &CameraRays, sampler: &PixelSampler, sample: Sample) -> Ray {
        let jitter = sampler.get_2d(dim::PIXEL, sample.s, self.ctx.spp);
        film::camera_ray(rays, sample, jitter)
    }
}

impl PixelEstimator for PhotonEstimator<'_> {
    type Row = SampleScratch;
    /// The pixel's points, and its gather rays per sample.
    type Pixel = (PixelSampler, u32);

    fn row(&self) -> SampleScratch {
        SampleScratch::new(self.k)
    }

    fn pixel(&self, key: u64, x: u32, y: u32) -> (PixelSampler, u32) {
        let g = self.plan.map_or(self.ctx.gather, |p| p.count(x, y));
        (PixelSampler::new(key), g)
    }

    fn radiance(
        &self,
        rays: &CameraRays,
        (sampler, g): &(PixelSampler, u32),
        sample: Sample,
        rng: &mut Rng,
        sc: &mut SampleScratch,
    ) -> Vec3 {
        let ray = self.camera_ray(rays, sampler, sample);
        self.ctx.radiance(ray, (sampler, sample.s), *g, rng, sc)
    }

    fn radiance_batch(
        &self,
        rays: &CameraRays,
        pixel: &(PixelSampler, u32),
        samples: &[Sample],
        rngs: &mut [Rng],
        sc: &mut SampleScratch,
        out: &mut [Vec3],
    ) {
        let (sampler, g) = pixel;
        if !self.ctx.batches() {
            film::one_by_one(self, rays, pixel, samples, rngs, sc, out);
            return;
        }
        // The batch's buffers live in the row's scratch, out of it meanwhile.
        let mut batch = std::mem::take(&mut sc.batch);
        batch.start(
            *g,
            samples
                .iter()
                .map(|&sample| (sample.s, self.camera_ray(rays, sampler, sample))),
        );
        self.ctx.radiance_batch(sampler, rngs, sc, &mut batch, out);
        sc.batch = batch;
    }

    fn row_done(&self, sc: SampleScratch) {
        self.lookup_ns.fetch_add(sc.lookup_ns, Ordering::Relaxed);
        self.hits.fetch_add(sc.hits, Ordering::Relaxed);
        self.misses.fetch_add(sc.misses, Ordering::Relaxed);
        if let Some(reads) = self.ctx.reads {
            reads.merge(&sc.reads);
        }
    }
}
