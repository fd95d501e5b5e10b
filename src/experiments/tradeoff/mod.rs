//! The speed/accuracy trade (docs/method.md, "The speed-accuracy trade";
//! issue 10): error against an unbiased reference, against time and memory,
//! for the contenders ([`Contender`]: the paper's three modes, and the
//! adaptive mode with importance in its counts) over a range of budgets and
//! several seeds.
//!
//! # The reference
//! The path tracer ([`crate::render::path`]), never one of the competitors,
//! rendered as two independent halves; its relative noise is `rmse(A, B) / 2
//! / mean` per measured quantity. It must be below a third of the smallest
//! error it judges ([`NOISE_RATIO`]): otherwise [`run_tradeoff`] fails with
//! [`crate::Error::InvalidParameter`] naming the numbers and the `spp` to ask
//! for. It is cached under [`TradeoffConfig::cache_dir`] by a hash of the
//! scene's *content* (geometry, materials, lights, camera: the same scene
//! under another path or name hits the cache; an edited one does not) and of
//! the reference settings.
//!
//! # The errors (each against the reference)
//! - (a) `indirect_rel_rmse`: the indirect light at the first non-delta hit,
//!   the photon map's whole share of the image. The photon render's indirect
//!   part is its full render minus its direct-only render *with the same seed*
//!   (both draw the same light samples, so the difference is the map's
//!   estimate exactly); the path tracer's is
//!   [`crate::render::PathPart::Indirect`].
//! - (b) `image_rel_rmse`: the full image (emitters hidden).
//! - (c) `points_rel_err`: irradiance at [`TradeoffConfig::points`] fixed
//!   area-uniform points on the surfaces that neither emit nor are specular
//!   (a map stores nothing on mirrors and glass), read from the full map
//!   alone (no pixels, no light sampling); the reference is the direct
//!   light's quadrature plus path-traced indirect irradiance.
//!
//! Image errors are relative RMSE over the pixels that are not a light (a
//! light's own pixels are exact in every renderer and would dominate the
//! norm): `sqrt(mean (a - r)^2) / mean(r)`. `k` of every estimate grows as
//! `sqrt(N_MAX) / 2` (20..=1000) so that noise and kernel bias both fall.
//!
//! # Bias and variance
//! Over the seeds of one mode and budget: `spread` is the rms deviation of
//! each seed's result from the seeds' mean (corrected by `S / (S - 1)`), and
//! `bias` the error of that mean with the spread's share and the reference's
//! noise removed (`bias^2 = err(mean)^2 - spread^2 / S - noise_ref^2`,
//! floored at 0).
//!
//! # The two axes
//! `time_s` is trace (with the analysis, and the importance pass where
//! there is one: `importance_s`) + kd-trees + the full render, on
//! the pool the study runs in (the thread count is reported); `map_bytes` the
//! kd-trees the renderer keeps (the full and the indirect map). Equal-time
//! and equal-memory comparisons interpolate each mode's mean indirect error
//! log-log at one level per budget ([`summary`]).
//!
//! # The read share
//! `read_share`: of the photons stored in the maps the renderer keeps, the
//! fraction that at least one k-nearest lookup of the full render returns (a
//! pixel's first-hit estimate, a gather ray's estimate on a cache miss, the
//! irradiance cache's build estimates), each photon counted once however
//! many maps hold it ([`crate::render::reads`]). `read_share_pixels` leaves
//! the cache's build out: the cache estimates a cell at every photon sample,
//! seen or not, so with it nearly every photon is read. The timed render is
//! the one that marks them (a bit set per photon returned: +10-15 % of
//! `render_s` in docs/rendering.md's paired runs).
//!
//! # The estimated error
//! `estimated_rel_err` needs no reference: two extra traces at `N_MAX / 2`
//! with independent seeds, the points' irradiance read from each,
//! `rms(E_A - E_B) / sqrt(2) / mean`: the noise of one map of that budget. It
//! sees no kernel bias; how well it tracks `points_rel_err` is reported as
//! the ratio over the runs. [`knob`] uses it to pick Q for an error target.

pub mod contender;
pub mod knob;
mod measure;
pub mod output;
mod reference;
pub mod summary;

pub use contender::Contender;
pub use measure::{k_for, rel_rmse};
pub use reference::{scene_hash, Reference, ReferenceInfo};

use crate::error::{Error, Result};
use crate::scene::Scene;
use serde::Serialize;
use std::path::PathBuf;
use std::sync::Arc;

/// The reference noise must be below this fraction of the smallest error it judges.
pub const NOISE_RATIO: f64 = 1.0 / 3.0;

/// What the study runs.
#[derive(Clone, Debug, PartialEq)]
pub struct TradeoffConfig {
    /// `N_MAX` of each budget level, ascending.
    pub budgets: Vec<u64>,
    /// The contenders compared.
    pub modes: Vec<Contender>,
    /// Seeds per mode and budget (bias and variance are separated over them).
    pub seeds: u32,
    /// Image size of every render (and of the reference).
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Samples per pixel of the photon renders.
    pub spp: u32,
    /// Samples per pixel of each half of the path-traced reference.
    pub reference_spp: u32,
    /// Fixed surface points of error (c).
    pub points: usize,
    /// Path-traced rays per point and half of the points' reference.
    pub point_samples: u32,
    /// Where the reference is cached (`None`: not cached).
    pub cache_dir: Option<PathBuf>,
    /// Embree's kernel set (`None`: [`Device::new`](crate::embree::Device::new)'s choice).
    pub embree_isa: Option<crate::isa::Isa>,
    /// Where the renders' gather directions come from (the studies in
    /// `docs/tradeoff/` drew them by the BRDF, the default here; the
    /// renderer's own default is the cache's guide).
    pub gather_directions: crate::render::GatherDirections,
}

impl Default for TradeoffConfig {
    /// The defaults: `bench tradeoff cornell-empty` in under 5 minutes on 2 cores.
    fn default() -> Self {
        TradeoffConfig {
            budgets: vec![10_000, 40_000, 160_000],
            modes: Contender::ALL.to_vec(),
            seeds: 3,
            width: 32,
            height: 32,
            // The renderer gathers (one ray per camera sample, through the
            // irradiance cache): at 4 spp its own noise, ~0.45 relRMSE, hid
            // every budget's map error; at 256 spp the map's error decides
            // (indirect error falls 42-47 % over the budgets on
            // cornell-empty), and the reference then needs 2 x 32768 spp to
            // stay under a third of the smallest error.
            spp: 256,
            reference_spp: 32_768,
            points: 128,
            point_samples: 4096,
            cache_dir: None,
            embree_isa: None,
            gather_directions: crate::render::GatherDirections::Brdf,
        }
    }
}

impl TradeoffConfig {
    /// Checks the settings.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the first bad one.
    pub fn validate(&self) -> Result<()> {
        if self.budgets.is_empty() || self.budgets.contains(&0) {
            return Err(Error::param(
                "budgets",
                "need at least one, each N_MAX >= 1",
            ));
        }
        if self.modes.is_empty() {
            return Err(Error::param("modes", "need at least one"));
        }
        if self.seeds == 0 || self.seeds > 64 {
            return Err(Error::param("seeds", "must be in 1..=64"));
        }
        if self.points == 0 || self.point_samples == 0 {
            return Err(Error::param("points", "need at least one point and sample"));
        }
        if self.reference_spp == 0 {
            return Err(Error::param("reference spp", "must be at least 1"));
        }
        self.render_config(self.spp, 1).check().map(drop)
    }

    /// A render of this study's size: emitters hidden, one gather ray per
    /// camera sample (the study's spp and reference were sized for one, and
    /// the studies in `docs/tradeoff/` were measured with it; the render's
    /// default is two), drawn as [`Self::gather_directions`] says.
    pub fn render_config(&self, spp: u32, seed: u64) -> crate::render::RenderConfig {
        let mut c = crate::render::RenderConfig::new(self.width, self.height);
        c.spp = spp;
        c.seed = seed;
        c.show_emitters = false;
        c.final_gather = 1;
        c.gather_directions = self.gather_directions;
        c
    }
}

/// One run: a contender, a budget, a seed.
#[derive(Clone, Debug, Serialize)]
pub struct Run {
    /// The contender.
    pub mode: Contender,
    /// `sqrt(N_MAX / INT_MAX)`.
    pub quality: f64,
    /// The budget.
    pub n_max: u64,
    /// The seed.
    pub seed: u64,
    /// Photons stored.
    pub photons: usize,
    /// Photons per estimate.
    pub k: usize,
    /// Trace seconds (with the analysis and the importance pass).
    pub trace_s: f64,
    /// Seconds of the importance pass, a part of `trace_s` (0 without one).
    pub importance_s: f64,
    /// kd-tree seconds.
    pub build_s: f64,
    /// Full render seconds.
    pub render_s: f64,
    /// `trace_s + build_s + render_s`.
    pub time_s: f64,
    /// Bytes of the kept kd-trees (full + indirect map).
    pub map_bytes: usize,
    /// (a) indirect light, relative RMSE over non-light pixels.
    pub indirect_rel_rmse: f64,
    /// (b) full image, relative RMSE over non-light pixels.
    pub image_rel_rmse: f64,
    /// (c) irradiance at the fixed points from the map alone, relative RMSE.
    pub points_rel_err: f64,
    /// (c) estimated without a reference from two half-maps.
    pub estimated_rel_err: f64,
    /// Share of the stored photons that some lookup of the full render
    /// returned (see the module docs).
    pub read_share: f64,
    /// The same without the irradiance cache's build lookups: the photons
    /// that pixels and gather rays read themselves.
    pub read_share_pixels: f64,
}

/// Everything the study measured.
#[derive(Clone, Debug, Serialize)]
pub struct TradeoffResults {
    /// The scene's name or path as given.
    pub scene: String,
    /// The reference.
    pub reference: ReferenceInfo,
    /// Every run, by contender, then budget, then seed.
    pub runs: Vec<Run>,
    /// Per contender and budget, over the seeds.
    pub groups: Vec<summary::Group>,
    /// Equal-time comparison, one entry per budget level.
    pub equal_time: Vec<summary::Level>,
    /// Equal-memory comparison, one entry per budget level.
    pub equal_memory: Vec<summary::Level>,
    /// `points_rel_err / estimated_rel_err` over the runs.
    pub estimate_tracking: summary::Tracking,
    /// Worker threads of the pool the study ran on.
    pub threads: usize,
    /// Where the renders' gather directions came from (`brdf` or `guided`).
    pub gather_directions: &'static str,
    /// Wall-clock seconds of the whole study.
    pub elapsed_s: f64,
}

/// Progress of [`run_tradeoff`]: runs done of the total, and what runs now.
#[derive(Clone, Debug)]
pub struct Progress {
    /// Runs finished.
    pub done: usize,
    /// Runs in all.
    pub total: usize,
    /// What is being done.
    pub stage: String,
}

/// Runs the study on `scene` (named `name` in the output) on the current
/// rayon pool.
///
/// # Errors
/// Bad settings, a scene that cannot be traced, an unwritable cache, or a
/// reference too noisy for the smallest error it judges (see the module docs).
pub fn run_tradeoff(
    name: &str,
    scene: &Scene,
    cfg: &TradeoffConfig,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<TradeoffResults> {
    cfg.validate()?;
    let start = std::time::Instant::now();
    let device = crate::embree::Device::pinned_or_default(cfg.embree_isa)?;
    let prepared = Arc::new(scene.clone().commit(&device)?);
    let total = cfg.modes.len() * cfg.budgets.len() * cfg.seeds as usize;
    let say = |done: usize, stage: String| progress(Progress { done, total, stage });
    say(0, "path-traced reference".into());
    let reference = Reference::get(&prepared, cfg)?;
    let mut runs = Vec::with_capacity(total);
    let mut outputs = Vec::with_capacity(total);
    for &mode in &cfg.modes {
        for &n_max in &cfg.budgets {
            for s in 0..cfg.seeds as u64 {
                say(
                    runs.len(),
                    format!("{} N_MAX {n_max} seed {}", mode.name(), s + 1),
                );
                let (run, out) =
                    measure::measure_run(&prepared, cfg, &reference, mode, n_max, s + 1)?;
                runs.push(run);
                outputs.push(out);
            }
        }
    }
    say(total, "summary".into());
    let groups = summary::groups(&runs, &outputs, &reference, cfg);
    reference.check_noise(&runs)?;
    Ok(TradeoffResults {
        scene: name.to_string(),
        equal_time: summary::equal(&groups, &cfg.modes, cfg.budgets.len(), summary::Axis::Time),
        equal_memory: summary::equal(
            &groups,
            &cfg.modes,
            cfg.budgets.len(),
            summary::Axis::Memory,
        ),
        estimate_tracking: summary::tracking(&runs),
        reference: reference.info.clone(),
        runs,
        groups,
        threads: rayon::current_num_threads(),
        gather_directions: cfg.gather_directions.name(),
        elapsed_s: start.elapsed().as_secs_f64(),
    })
}
