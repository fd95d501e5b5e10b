//! Images from the photon map: a pinhole camera, direct light by sampling the
//! emitters, indirect light from the photon map, optional final gather, and
//! the image files (OpenEXR, tone-mapped PNG).
//!
//! The renderer reads rays through the [`RayCaster`](crate::raycast::RayCaster)
//! of a [`PreparedScene`](crate::scene::PreparedScene): Embree's (feature
//! `embree`, below) or a renderer's own, with no feature at all.
//!
//! ```no_run
//! # #[cfg(all(feature = "embree", feature = "gltf", feature = "image-io"))] {
//! use adaptive_pm::embree::Device;
//! use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
//! use adaptive_pm::render::{render, RenderConfig, RenderMaps};
//! use adaptive_pm::scene::Scene;
//!
//! let tracer = Tracer::new(Scene::cornell()?.commit(&Device::new()?)?);
//! let run = tracer.trace(&TraceConfig::new(Mode::Adaptive, Budget::NMax(100_000)))?;
//! let maps = RenderMaps::build(&run.records());
//! let cfg = RenderConfig::new(64, 64);
//! let image = render(tracer.prepared(), Some(&maps), &cfg)?;
//! image.write_exr("cornell.exr")?;
//! # }
//! # Ok::<(), adaptive_pm::Error>(())
//! ```
//!
//! # The estimator ([`View::Full`])
//! A camera ray follows mirrors and glass (at most [`MAX_SPECULAR`] bounces,
//! one sampled direction each: reflection or refraction by Fresnel) to its
//! first non-specular hit `x`, as pbrt-v4's SPPM places its visible point.
//! The pixel's radiance is (Jensen's decomposition)
//! - the emission of an emitter the (possibly mirrored) ray reaches, `L0 cos^n`
//!   (`L0` the texel's there, for an emissive texture);
//! - **direct light** at `x`: one sample per light and pixel sample (area
//!   lights: an area-uniform point, or on a textured light one drawn by
//!   emitted power, the `cos^n` radiance over the point's pdf, a shadow ray;
//!   point and spot lights: their intensity over `r^2` and a shadow ray;
//!   directional lights: their irradiance and a shadow ray unbounded
//!   towards them);
//! - **caustics** at `x` (`L S+ x`, light that came through mirrors and
//!   glass only): the radiance estimate of the **caustic map** (the photons
//!   flagged caustic by the tracer, or those of a caustic pass aimed at the
//!   specular objects: [`crate::engine::Maps::with_caustic_pass`]) with its
//!   own, narrower kernel
//!   ([`RenderConfig::caustic_k`], [`RenderConfig::caustic_max_radius`]);
//! - **the rest of the indirect light** at `x`, either
//!   - without final gather: the radiance estimate of the photons stored at
//!     depth >= 1 that are not caustic photons (the **indirect map**).
//!     Depth-0 photons *are* the direct light, already counted by light
//!     sampling;
//!   - with final gather (`G` rays): `G` BRDF-sampled rays from `x`, each
//!     followed through mirrors and glass to a non-specular hit `y`, where
//!     the **full map** (all depths: the light leaving `y` includes its
//!     direct light and its own caustics) gives the radiance. A gather ray
//!     that reaches an emitter adds nothing: straight away it is the direct
//!     light, through a specular chain it is a caustic at `x`, both counted.
//!
//! The split is exact: every light path `L ... x E` is counted once.
//!
//! # The radiance estimate ([`estimate`])
//! The `k` nearest photons (default [`DEFAULT_K`]) that arrived on the shaded
//! side of the surface, within `max_radius`; each weighted by the BRDF for its
//! incident direction and by Jensen's **cone filter** `w = 1 - d / r`, whose
//! normalisation is `pi r^2 / 3`. `r` is the distance to the k-th photon, or
//! `max_radius` when fewer were found (then the estimate is a fixed-radius one).
//!
//! # Diagnostic views
//! [`View::DirectOnly`]: emission and direct light, no map.
//! [`View::Emitters`]: the emission the camera sees (through mirrors and
//! glass too), nothing else.
//! [`View::Map`]: emission and the map's radiance estimate at the first
//! non-delta hit, no light sampling, no gather: the full map, or with
//! `primary_only` the depth-0 photons (the paper's primary map).
//!
//! # Determinism
//! Pixel `p`'s sample `s` draws from `Rng::new(hash2(hash2(seed, p), s))`, so
//! an image does not depend on the thread count or the tiling.
//!
//! # Rays
//! Camera, shadow and gather rays go through the caster's
//! [`intersect`](crate::raycast::RayCaster::intersect) /
//! [`occluded`](crate::raycast::RayCaster::occluded) one at a time (with
//! Embree, `rtcIntersect1` / `rtcOccluded1`). The 16-wide
//! packets of the batched path gain at most ~10 % on coherent rays in scenes
//! this small (`cargo bench --bench rays`: 14.5 vs 14.7 Mrays/s on the
//! 12-triangle box, 8.9 vs 8.1 on the 49k one), while a sample spends most of
//! its time in the k-nearest photon lookup (k = 100..200, tens of
//! microseconds) next to ~0.1 µs per ray: batching the rays would not show.

mod batch;
pub mod cache;
mod camera;
pub mod direct;
pub mod estimate;
mod film;
#[cfg(test)]
mod gather_guide_tests;
mod gather_plan;
pub mod image;
pub(crate) mod importance_walk;
mod integrator;
pub mod metrics;
pub mod path;
mod path_light;
mod path_render;
pub mod progressive;
mod quadrature;
pub mod reads;
mod run;
pub mod sampler;

pub use cache::{CacheConfig, IrradianceCache};
pub use camera::CameraRays;
pub use direct::LightSampler;
pub use estimate::{irradiance_estimate, radiance_estimate, Estimate, Lookup};
pub use gather_plan::{GatherAllocation, GatherDirections, GatherPlan};
#[cfg(feature = "image-io")]
#[cfg_attr(docsrs, doc(cfg(feature = "image-io")))]
pub use image::ExrFile;
pub use image::{check_output_path, tile_rows, Image, ToneMap, MAX_DIMENSION};
pub use metrics::{mean_bias, relative_rmse_masked, rmse};
pub use path::{Integrator, PathPart, PathTracer};
pub use path_render::{
    indirect_irradiance, light_pixels, render_path, render_path_with, specular_pixels, PathHalves,
};
pub use progressive::{render_to_noise, NoiseTarget, Progressive, Round};
pub use quadrature::{floor_points, quadrature_irradiance, unshadowed_irradiance};
pub use reads::MapReads;
pub use run::{
    render, render_checked, render_halves_to_noise, render_progressive, render_reading,
    render_with, RenderStats,
};

use crate::error::{Error, Result};
use crate::scene::{Camera, Scene};

/// Render settings that passed [`RenderConfig::check`]: what
/// [`render_checked`] and the image loop run on, never checked again. Read
/// the settings through `Deref`.
#[derive(Clone, Debug)]
pub struct CheckedRender(RenderConfig);

impl std::ops::Deref for CheckedRender {
    type Target = RenderConfig;
    fn deref(&self) -> &RenderConfig {
        &self.0
    }
}

impl CheckedRender {
    /// The same settings with another seed (a seed is never invalid).
    pub fn with_seed(&self, seed: u64) -> Self {
        let mut c = self.clone();
        c.0.seed = seed;
        c
    }

    /// The same settings with the emitters hidden ([`RenderConfig::show_emitters`] off).
    pub fn without_emitters(&self) -> Self {
        let mut c = self.clone();
        c.0.show_emitters = false;
        c
    }
}

/// The photon maps a render reads: the one map set of a run
/// ([`crate::engine::Maps`]: full, indirect, primary, with build times).
pub type RenderMaps = crate::engine::Maps;

/// Default number of photons in a radiance estimate.
pub const DEFAULT_K: usize = 100;

/// Default number of caustic photons in a caustic estimate: fewer than
/// [`DEFAULT_K`], so the kernel stays as narrow as a caustic's features.
pub const DEFAULT_CAUSTIC_K: usize = 50;

/// Default largest caustic kernel radius, as a fraction of the largest
/// radius of the other estimates: a caustic is sharp where it is bright,
/// and where it is faint a wide kernel would spread it over its shadow.
pub const CAUSTIC_RADIUS_FRACTION: f32 = 0.25;

/// Default search radius as a fraction of the scene's bounding-box diagonal:
/// wide enough that only truly empty regions hit it.
pub const DEFAULT_MAX_RADIUS_FRACTION: f32 = 0.1;

/// Mirror bounces a camera or gather ray follows before it is dropped.
pub const MAX_SPECULAR: u32 = 8;

/// Most samples per pixel accepted.
pub const MAX_SPP: u32 = 1 << 16;

/// Most final-gather rays per hit accepted.
pub const MAX_GATHER: u32 = 4096;

/// Most light samples per camera sample accepted.
pub const MAX_LIGHT_SAMPLES: u32 = 1024;

/// Default final-gather rays per camera sample: two, stratified over the
/// pixel's samples (64 spp gather 128 directions per pixel). On the Cornell
/// box the gather's noise is most of the image's, and a second gather ray
/// costs less than a second camera sample (no camera ray, no light sample):
/// 3 % relRMSE at 256² took 96 spp and 2.74 s with two, 192 spp and 3.40 s
/// with one (`bench render cornell --size 256 --n-max 300000 --final-gather
/// G`, one session on an Intel Xeon: `docs/bench_render_gather2/`). Four
/// or more per sample lose again to the pixel's own noise (edges, direct
/// light) at the fewer samples.
pub const DEFAULT_GATHER: u32 = 2;

/// What the image shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// Emission + direct light + indirect light from the map (or the gather).
    Full,
    /// Emission + direct light only; no photon map needed.
    DirectOnly,
    /// Emission + the map's radiance estimate at the first non-delta hit.
    Map {
        /// Use only the depth-0 photons (the paper's primary map).
        primary_only: bool,
    },
    /// Emission the camera sees, directly or through mirrors and glass,
    /// and nothing else; no photon map needed. `--spp auto` adds it to an
    /// image rendered without it, so that the aliasing of a light's edges
    /// stays out of the noise it measures.
    Emitters,
}

/// How to render.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderConfig {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel (jittered positions; one light sample each).
    pub spp: u32,
    /// Final-gather rays per camera sample (0 = read the indirect map at the
    /// first hit): in every pixel, or on average ([`RenderConfig::gather_allocation`]).
    pub final_gather: u32,
    /// How the gather's rays are spread over the pixels.
    pub gather_allocation: GatherAllocation,
    /// Where the gather's directions come from at a diffuse surface.
    pub gather_directions: GatherDirections,
    /// Light samples (shadow rays) per camera sample.
    pub light_samples: u32,
    /// The irradiance cache the gather reads: one entry per `cache_stride`
    /// photons; 0 reads the full map's k-nearest estimate instead.
    pub cache_stride: u32,
    /// Photons per radiance estimate.
    pub k: usize,
    /// Caustic photons per caustic estimate (the caustic map's own kernel).
    pub caustic_k: usize,
    /// Largest caustic kernel radius (world units); `None` is
    /// [`CAUSTIC_RADIUS_FRACTION`] of the other estimates' largest radius.
    pub caustic_max_radius: Option<f32>,
    /// Largest search radius (world units); `None` is
    /// [`DEFAULT_MAX_RADIUS_FRACTION`] of the scene's diagonal.
    pub max_radius: Option<f32>,
    /// What to show.
    pub view: View,
    /// Seed of the pixel samples.
    pub seed: u64,
    /// The camera; `None` is the scene's camera (a scene without one is an
    /// error: there is no silent default view).
    pub camera: Option<Camera>,
    /// Show the emission of emitters the camera sees (directly or in mirrors).
    /// Error measurements turn it off: the emission is exact and the same in
    /// every mode, but the aliasing of a bright light's edges would dominate
    /// an image RMSE.
    pub show_emitters: bool,
    /// Render only rows `start..end` of the image (a tile, `render --tile`);
    /// each pixel is the same as in the whole image. `None`: every row.
    pub rows: Option<(u32, u32)>,
}

impl RenderConfig {
    /// A `width x height` full render, 1 sample per pixel, defaults elsewhere
    /// (a final gather through the irradiance cache).
    pub fn new(width: u32, height: u32) -> Self {
        RenderConfig {
            width,
            height,
            spp: 1,
            final_gather: DEFAULT_GATHER,
            gather_allocation: GatherAllocation::default(),
            gather_directions: GatherDirections::default(),
            light_samples: 1,
            cache_stride: cache::DEFAULT_STRIDE,
            k: DEFAULT_K,
            caustic_k: DEFAULT_CAUSTIC_K,
            caustic_max_radius: None,
            max_radius: None,
            view: View::Full,
            seed: 1,
            camera: None,
            show_emitters: true,
            rows: None,
        }
    }

    /// True when these settings read the primary or the indirect map (the
    /// primary-only map view, or indirect light from the k nearest photons
    /// without a gather); else the full map is all the render reads, and
    /// [`Maps::full_only`](crate::engine::Maps::full_only) is enough.
    pub fn reads_split_maps(&self) -> bool {
        match self.view {
            View::Map { primary_only } => primary_only,
            View::Full => self.final_gather == 0,
            View::DirectOnly | View::Emitters => false,
        }
    }

    /// The maps these settings read, built from a trace's compact photons:
    /// all three when [`RenderConfig::reads_split_maps`], else the full map
    /// alone ([`Maps::full_only`](crate::engine::Maps::full_only)).
    pub fn build_maps(
        &self,
        photons: Vec<crate::photon_map::CompactPhoton>,
        frame: crate::photon_map::Quantizer,
    ) -> RenderMaps {
        if self.reads_split_maps() {
            RenderMaps::from_photons(photons, frame)
        } else {
            RenderMaps::full_only(photons, frame)
        }
    }

    /// Checks every setting once, including that the image fits in memory:
    /// the form the renderer runs on ([`render_checked`]).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the first bad setting.
    pub fn check(&self) -> Result<CheckedRender> {
        self.validate()?;
        Ok(CheckedRender(self.clone()))
    }

    fn validate(&self) -> Result<()> {
        image::check_dimensions(self.width, self.height)?;
        if self.spp == 0 || self.spp > MAX_SPP {
            return Err(Error::param(
                "spp",
                format!("must be in 1..={MAX_SPP}, got {}", self.spp),
            ));
        }
        if self.final_gather > MAX_GATHER {
            return Err(Error::param(
                "final gather",
                format!("must be at most {MAX_GATHER}, got {}", self.final_gather),
            ));
        }
        if self.light_samples == 0 || self.light_samples > MAX_LIGHT_SAMPLES {
            return Err(Error::param(
                "light samples",
                format!(
                    "must be in 1..={MAX_LIGHT_SAMPLES} per camera sample, got {}",
                    self.light_samples
                ),
            ));
        }
        if self.cache_stride == 1 || self.cache_stride > cache::MAX_STRIDE {
            return Err(Error::param(
                "cache stride",
                format!(
                    "must be 0 (no cache) or in {}..={} photons per cache entry, got {}",
                    cache::MIN_STRIDE,
                    cache::MAX_STRIDE,
                    self.cache_stride
                ),
            ));
        }
        if self.k == 0 || self.k > 10_000 {
            return Err(Error::param(
                "k",
                format!("must be in 1..=10000, got {}", self.k),
            ));
        }
        if self.caustic_k == 0 || self.caustic_k > 10_000 {
            return Err(Error::param(
                "caustic k",
                format!("must be in 1..=10000, got {}", self.caustic_k),
            ));
        }
        if let Some((a, b)) = self.rows {
            if a >= b || b > self.height {
                return Err(Error::param(
                    "rows",
                    format!("{a}..{b} is not a non-empty range of 0..{}", self.height),
                ));
            }
        }
        for (name, r) in [
            ("max radius", self.max_radius),
            ("caustic max radius", self.caustic_max_radius),
        ] {
            if let Some(r) = r {
                if !(r.is_finite() && r > 0.0) {
                    return Err(Error::param(
                        name,
                        format!("must be a positive number, got {r}"),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The camera this render uses for `scene`: [`RenderConfig::camera`], else the scene's.
    ///
    /// # Errors
    /// [`Error::InvalidScene`] when neither gives one.
    pub fn camera_for(&self, scene: &Scene) -> Result<Camera> {
        self.camera.or(scene.camera).ok_or_else(|| {
            Error::InvalidScene(
                "the scene has no camera: give the render one (RenderConfig::camera)".into(),
            )
        })
    }
}

/// The default search radius of `scene`.
pub fn default_max_radius(scene: &Scene) -> f32 {
    let (lo, hi) = scene.bounds();
    let d = (hi - lo).length();
    if d.is_finite() && d > 0.0 {
        DEFAULT_MAX_RADIUS_FRACTION * d
    } else {
        1.0
    }
}

/// Offset of secondary ray origins: a small fraction of the scene's size.
pub(crate) fn ray_epsilon(scene: &Scene) -> f32 {
    scene.ray_epsilon()
}
