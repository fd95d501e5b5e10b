//! The paper's experiments (docs/method.md, "The experiments"): a Cornell
//! box (by default the built-in `cornell-empty`, the paper's scene: walls and
//! light, no blocks; or `cornell`, or any glTF with one area light), its
//! light's `cos^n` exponent swept, every mode traced at each `n` with the
//! same `N_MAX`.
//!
//! - **Reference**: the classic mode with a diffuse light (n = 0), traced first.
//!   Its primary map's max density is Fig. 7a's reference line, its full map's
//!   sigma Fig. 9a's, and its primary map's max density is the
//!   density-control target of every density-mode run (docs/method.md,
//!   "Density control"; `mean`, its full map's mean density, is the other
//!   choice). When the sweep itself has the classic run at n = 0,
//!   that run *is* the reference (same seed, same photons) and is not traced twice.
//! - **One trace per run** gives both maps: records carry their depth, and
//!   [`Maps::build`] builds the primary-only and the full kd-tree.
//! - **Same evaluation points** for every run: only the light's exponent changes
//!   between runs, not the geometry, so the points are drawn once.
//! - **Reuse**: one Embree device and committed scene for the whole sweep (the
//!   geometry does not change with `n`), one [`Tracer`] per `n` over a copy of the
//!   scene with that `n`, sharing the Embree geometry (checked to match).
//! - **Runs in parallel, each on one thread**: the caller's pool size sets how
//!   many workers there are; each worker takes the next `n` and runs its modes
//!   on a one-thread pool of its own. Runs are independent, so this scales
//!   even for density control's sequential pass, and every time reported is a
//!   one-thread time, untouched by work stealing between runs. Results do not
//!   depend on the worker count (the engine is thread-count independent).
//! - **Both directionality estimators**: the run uses the configured one; the
//!   other's `alpha_D` is computed too (the analysis alone, no trace) so that
//!   `alpha_D(n) (n + 2) / 2` is reported for both ([`AlphaRow`]).

use crate::analysis::{analyze_emitter, AnalysisParams, Estimator};
use crate::embree::{CommittedScene, Device};
use crate::emitter::CosN;
use crate::engine::{density_points, map_density, Budget, DensityTarget, Maps, Mode};
use crate::engine::{TraceConfig, Tracer};
use crate::error::{Error, Result};
use crate::scene::{Light, PreparedScene, Scene, SurfacePoint};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// What the sweep runs.
#[derive(Clone, Debug)]
pub struct CornellConfig {
    /// The scene: a built-in name ([`crate::scene::builtin_names`]) or a glTF
    /// path; it must have exactly one area light.
    pub scene: String,
    /// The folder a glTF scene's external files may be read from (`None`:
    /// the scene file's folder; see [`crate::scene::LoadOptions`]).
    pub asset_root: Option<std::path::PathBuf>,
    /// Light exponents, in the order they are run (see [`super::sweep::parse_sweep`]).
    pub n_values: Vec<f64>,
    /// `N_MAX` of every run (the paper: 100 000).
    pub n_max: u64,
    /// Modes run at each `n` (the reference classic run at n = 0 is always made).
    pub modes: Vec<Mode>,
    /// Seed of every run (runs at different `n` share it).
    pub seed: u64,
    /// The estimator that sets `alpha_D` in the adaptive runs.
    pub estimator: Estimator,
    /// Bounce limit of every run.
    pub max_depth: u32,
    /// Density control's target in the density-mode runs.
    pub density_target: SweepDensityTarget,
    /// Embree's kernel set, pinned so that the sweep's photons do not depend
    /// on the CPU (`None`: [`Device::new`]'s choice).
    pub embree_isa: Option<crate::isa::Isa>,
}

/// Where the density-mode runs of a sweep put their target density.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SweepDensityTarget {
    /// The reference's full-map *mean* density: density control then caps
    /// every map near the mean, far below the reference's max.
    ReferenceMean,
    /// The reference's primary-map *max* density (Fig. 7a's reference line;
    /// the default, docs/method.md, "Density control": density control then
    /// limits the map to the reference, the paper's reading).
    ReferenceMax,
    /// A given density, photons per unit area (> 0).
    PerArea(f64),
}

impl std::str::FromStr for SweepDensityTarget {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "mean" => Ok(SweepDensityTarget::ReferenceMean),
            "max" => Ok(SweepDensityTarget::ReferenceMax),
            _ => match s.parse::<f64>() {
                Ok(d) if d.is_finite() && d > 0.0 => Ok(SweepDensityTarget::PerArea(d)),
                _ => Err(Error::param(
                    "density target",
                    format!(
                        "`{s}` is not `mean`, `max` or a positive number of photons per unit area"
                    ),
                )),
            },
        }
    }
}

impl CornellConfig {
    /// The paper's setting: `n` = 1..=200, `N_MAX` = 100 000, the three modes,
    /// the paper's estimator.
    pub fn paper() -> Self {
        CornellConfig {
            scene: crate::scene::BUILTIN_CORNELL_EMPTY.to_string(),
            asset_root: None,
            n_values: (1..=200).map(f64::from).collect(),
            n_max: crate::engine::config::PAPER_N_MAX,
            modes: Mode::ALL.to_vec(),
            seed: 1,
            estimator: Estimator::Paper,
            max_depth: crate::engine::config::DEFAULT_MAX_DEPTH,
            density_target: SweepDensityTarget::ReferenceMax,
            embree_isa: None,
        }
    }

    /// Checks the settings before anything is traced.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for an empty sweep or mode list, an exponent
    /// that is not finite and >= 0, or a bad trace setting.
    pub fn validate(&self) -> Result<()> {
        if self.n_values.is_empty() {
            return Err(Error::param("n sweep", "holds no value"));
        }
        if self.modes.is_empty() {
            return Err(Error::param("modes", "holds no mode"));
        }
        for &n in &self.n_values {
            CosN::new(n as f32)?;
        }
        self.trace_config(Mode::Classic).validate()
    }

    /// How the sweep's scene file is loaded.
    pub fn load_options(&self) -> crate::scene::LoadOptions {
        crate::scene::LoadOptions {
            asset_root: self.asset_root.clone(),
        }
    }

    fn trace_config(&self, mode: Mode) -> TraceConfig {
        let mut cfg = TraceConfig::new(mode, Budget::NMax(self.n_max));
        cfg.seed = self.seed;
        cfg.estimator = self.estimator;
        cfg.max_depth = self.max_depth;
        cfg
    }

    /// Traces the sweep makes: the reference, plus every (n, mode) pair but the
    /// classic run at n = 0 that the reference stands for.
    pub fn run_count(&self) -> usize {
        let reused = usize::from(self.modes.contains(&Mode::Classic))
            * self.n_values.iter().filter(|&&n| n == 0.0).count();
        1 + self.n_values.len() * self.modes.len() - reused
    }
}

/// Every metric of one run (docs/method.md, "The photon map and its
/// measurements"). Densities are photons per unit area of the scene (the
/// built-in box is in millimetres: photons / mm^2).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct RunMetrics {
    /// The light's exponent.
    pub n: f64,
    /// The mode.
    pub mode: Mode,
    /// `N_MAX`.
    pub n_max: u64,
    /// Photons emitted by the light.
    pub emitted: u64,
    /// Photons stored, all depths.
    pub stored: u64,
    /// Photons stored at their first hit (the primary map).
    pub stored_primary: u64,
    /// Photons re-emitted from first hits (Fig. 8).
    pub reemitted_first_hit: u64,
    /// Mean children per hit at each depth, depth 0 first (Fig. 9b). The last
    /// entry at `max_depth` is 0 by construction: paths stop there.
    pub split_rate_by_depth: Vec<f64>,
    /// Hits per depth (the denominators of the split rates).
    pub hits_by_depth: Vec<u64>,
    /// Max density of the primary map over the evaluation points (Fig. 7a).
    pub max_density_primary: f64,
    /// Mean density of the primary map.
    pub mean_density_primary: f64,
    /// Standard deviation of the primary map's density.
    pub sigma_density_primary: f64,
    /// `sigma / mean` of the primary map's density.
    pub sigma_over_mean_primary: f64,
    /// Max density of the full map.
    pub max_density: f64,
    /// Mean density of the full map.
    pub mean_density: f64,
    /// Standard deviation of the full map's density (Fig. 9a).
    pub sigma_density: f64,
    /// `sigma / mean` of the full map's density (Fig. 9a, normalised).
    pub sigma_over_mean: f64,
    /// Seconds to trace every depth.
    pub trace_s: f64,
    /// Seconds to trace wave 0 (emission and first hits).
    pub trace_primary_s: f64,
    /// Seconds to build the full kd-tree.
    pub build_s: f64,
    /// Seconds to build the primary kd-tree.
    pub build_primary_s: f64,
    /// Time to have the primary map: `trace_primary_s + build_primary_s` (Fig. 7b).
    pub primary_map_time_s: f64,
    /// Seconds to evaluate both maps' densities.
    pub measure_s: f64,
    /// True when the memory budget bound.
    pub budget_bound: bool,
    /// Hits where the per-hit split cap bound.
    pub capped_hits: u64,
    /// Photons density control refused (their power went to neighbours).
    pub density_rejected: u64,
    /// `alpha_D` the run used for the light (1 in the classic and density modes).
    pub alpha_d: f64,
    /// `alpha_D` of the light by the paper's estimator (whatever the run used).
    pub alpha_d_paper: f64,
    /// `alpha_D` of the light by the peak-density estimator.
    pub alpha_d_peak: f64,
    /// Mesh holding the evaluation point of the primary map's max density.
    pub max_density_primary_mesh: String,
    /// That point (scene units).
    pub max_density_primary_at: [f64; 3],
}

/// `alpha_D` of the light at one `n`, both estimators, and how far each is
/// from the value `2 / (n + 2)` that keeps the peak density of the emitted
/// directions equal to a diffuse light's (1 = exact).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct AlphaRow {
    /// The exponent.
    pub n: f64,
    /// The paper's estimator.
    pub alpha_d_paper: f64,
    /// The peak-density estimator.
    pub alpha_d_peak: f64,
    /// `alpha_d_paper * (n + 2) / 2`.
    pub ratio_paper: f64,
    /// `alpha_d_peak * (n + 2) / 2`.
    pub ratio_peak: f64,
}

/// Wall time of one mode's runs, summed over the sweep.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct ModeTiming {
    /// The mode.
    pub mode: Option<Mode>,
    /// Runs.
    pub runs: usize,
    /// Photons emitted, all runs.
    pub emitted: u64,
    /// Seconds tracing.
    pub trace_s: f64,
    /// Seconds building both kd-trees.
    pub build_s: f64,
    /// Seconds evaluating densities.
    pub measure_s: f64,
}

/// Everything a sweep measured.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CornellResults {
    /// The scene's name as given (`cornell-empty`, `cornell` or a path).
    pub scene: String,
    /// `N_MAX`.
    pub n_max: u64,
    /// The seed.
    pub seed: u64,
    /// The estimator of the adaptive runs.
    pub estimator: String,
    /// The bounce limit.
    pub max_depth: u32,
    /// The modes, in order.
    pub modes: Vec<Mode>,
    /// The exponents, in order.
    pub n_values: Vec<f64>,
    /// The classic run with a diffuse light.
    pub reference: RunMetrics,
    /// Every run, `n` major, modes in the configured order.
    pub runs: Vec<RunMetrics>,
    /// `alpha_D` per `n`, both estimators.
    pub alpha: Vec<AlphaRow>,
    /// Seconds of the directionality analyses of both estimators.
    pub analysis_s: f64,
    /// Time per mode (the reference is counted under classic).
    pub timing: Vec<ModeTiming>,
    /// Traces actually made.
    pub traces: usize,
    /// Wall time of the whole sweep.
    pub elapsed_s: f64,
}

impl CornellResults {
    /// Fig. 7a's reference line: the reference run's primary max density.
    pub fn reference_max_density(&self) -> f64 {
        self.reference.max_density_primary
    }

    /// Fig. 9a's reference: the reference run's full-map sigma.
    pub fn reference_sigma_density(&self) -> f64 {
        self.reference.sigma_density
    }

    /// The run of `mode` at the `i`-th exponent of the sweep.
    pub fn run(&self, i: usize, mode: Mode) -> Option<&RunMetrics> {
        let m = self.modes.iter().position(|&x| x == mode)?;
        self.runs.get(i * self.modes.len() + m)
    }

    /// The runs of one mode, in sweep order.
    pub fn mode_runs(&self, mode: Mode) -> Vec<&RunMetrics> {
        (0..self.n_values.len())
            .filter_map(|i| self.run(i, mode))
            .collect()
    }

    /// Photons emitted by every trace made.
    pub fn photons_emitted(&self) -> u64 {
        self.timing.iter().map(|t| t.emitted).sum()
    }
}

/// Where the Cornell sweep is, for a progress bar.
#[derive(Clone, Copy, Debug)]
pub struct CornellProgress {
    /// Traces finished.
    pub done: usize,
    /// Traces in the sweep.
    pub total: usize,
    /// Exponent of the run under way.
    pub n: f64,
    /// Mode of the run under way.
    pub mode: Mode,
}

fn alpha_rows(n_values: &[f64], params: &AnalysisParams) -> Result<Vec<AlphaRow>> {
    n_values
        .par_iter()
        .map(|&n| {
            let e = CosN::new(n as f32)?;
            let paper = analyze_emitter(&e, Estimator::Paper, params)?.alpha_d as f64;
            let peak = analyze_emitter(&e, Estimator::PeakDensity, params)?.alpha_d as f64;
            let k = (n + 2.0) / 2.0;
            Ok(AlphaRow {
                n,
                alpha_d_paper: paper,
                alpha_d_peak: peak,
                ratio_paper: paper * k,
                ratio_peak: peak * k,
            })
        })
        .collect()
}

/// One trace, its maps and their densities.
fn run_one(
    tracer: &Tracer<&CommittedScene>,
    cfg: &TraceConfig,
    n: f64,
    points: &[SurfacePoint],
    mesh_names: &[String],
    alpha: &AlphaRow,
) -> Result<RunMetrics> {
    let out = tracer.trace(cfg)?;
    let maps = Maps::from_photons(out.photons, out.frame);
    let t = Instant::now();
    let full = map_density(&maps.full, points);
    let primary = map_density(&maps.primary, points);
    let at = points.get(primary.argmax);
    let measure_s = t.elapsed().as_secs_f64();
    let r = out.report;
    let alpha_d = out.plans.first().map_or(1.0, |p| p.alpha_d as f64);
    Ok(RunMetrics {
        n,
        mode: cfg.mode,
        n_max: r.n_max,
        emitted: r.emitted,
        stored: r.stored,
        stored_primary: r.stored_primary,
        reemitted_first_hit: r.reemitted_first_hit,
        split_rate_by_depth: r.split_rate_by_depth,
        hits_by_depth: r.depths.iter().map(|d| d.hits).collect(),
        max_density_primary: primary.max,
        mean_density_primary: primary.mean,
        sigma_density_primary: primary.sigma,
        sigma_over_mean_primary: primary.sigma_over_mean,
        max_density: full.max,
        mean_density: full.mean,
        sigma_density: full.sigma,
        sigma_over_mean: full.sigma_over_mean,
        trace_s: r.trace_s,
        trace_primary_s: r.trace_primary_s,
        build_s: maps.build_s,
        build_primary_s: maps.build_primary_s,
        primary_map_time_s: r.trace_primary_s + maps.build_primary_s,
        measure_s,
        budget_bound: r.budget_bound,
        capped_hits: r.capped_hits,
        density_rejected: r.density_rejected,
        alpha_d,
        alpha_d_paper: alpha.alpha_d_paper,
        alpha_d_peak: alpha.alpha_d_peak,
        max_density_primary_mesh: at
            .and_then(|p| mesh_names.get(p.mesh))
            .cloned()
            .unwrap_or_default(),
        max_density_primary_at: at.map_or([0.0; 3], |p| p.position.as_dvec3().to_array()),
    })
}

/// The sweep's scene: exactly one light, an area light (the one whose
/// exponent the sweep varies).
fn sweep_scene(cfg: &CornellConfig) -> Result<Scene> {
    let scene = Scene::open_with(&cfg.scene, &cfg.load_options())?;
    let area_lights = scene
        .lights()
        .iter()
        .filter(|l| matches!(l, Light::Area(_)))
        .count();
    if area_lights != 1 || scene.lights().len() != 1 {
        return Err(Error::InvalidScene(format!(
            "the Cornell sweep needs a scene with exactly one light, an area light; `{}` has {} lights ({} area)",
            cfg.scene,
            scene.lights().len(),
            area_lights
        )));
    }
    Ok(scene)
}

/// One timing row per mode run, classic always (the reference is classic).
fn mode_timings(modes: &[Mode]) -> Vec<ModeTiming> {
    let mut timed = modes.to_vec();
    if !timed.contains(&Mode::Classic) {
        timed.push(Mode::Classic);
    }
    timed
        .iter()
        .map(|&m| ModeTiming {
            mode: Some(m),
            ..ModeTiming::default()
        })
        .collect()
}

/// Adds a run's times to its mode's row.
fn account(timing: &mut [ModeTiming], r: &RunMetrics) {
    if let Some(t) = timing.iter_mut().find(|t| t.mode == Some(r.mode)) {
        t.runs += 1;
        t.emitted += r.emitted;
        t.trace_s += r.trace_s;
        t.build_s += r.build_s + r.build_primary_s;
        t.measure_s += r.measure_s;
    }
}

/// Density control's settings, its target from the diffuse reference. A
/// diffuse classic run that stored nothing (N_MAX = 0) leaves no target:
/// density control then falls back to its automatic one.
fn density_config(cfg: &CornellConfig, reference: &RunMetrics) -> TraceConfig {
    let mut density_cfg = cfg.trace_config(Mode::Density);
    let target = match cfg.density_target {
        SweepDensityTarget::ReferenceMean => reference.mean_density,
        SweepDensityTarget::ReferenceMax => reference.max_density_primary,
        SweepDensityTarget::PerArea(d) => d,
    };
    if target > 0.0 && target.is_finite() {
        density_cfg.density_target = DensityTarget::PerArea(target);
    }
    density_cfg
}

/// `job(i)` for every `i < count`, each on one of `pools` (one thread each)
/// as they come free; the runs in the order of `i`, or the first error (the
/// jobs not started when one fails are skipped).
fn over_pools(
    pools: &[rayon::ThreadPool],
    count: usize,
    job: &(dyn Fn(usize) -> Result<Vec<RunMetrics>> + Sync),
) -> Result<Vec<RunMetrics>> {
    let next = AtomicUsize::new(0);
    let failed = AtomicBool::new(false);
    let slots: Vec<Mutex<Option<Result<Vec<RunMetrics>>>>> =
        (0..count).map(|_| Mutex::new(None)).collect();
    std::thread::scope(|s| {
        for pool in pools {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                if i >= count || failed.load(Ordering::Relaxed) {
                    break;
                }
                let r = pool.install(|| job(i));
                failed.fetch_or(r.is_err(), Ordering::Relaxed);
                if let Ok(mut slot) = slots[i].lock() {
                    *slot = Some(r);
                }
            });
        }
    });
    gather_runs(slots)
}

/// The runs of every `n`, in order, or the first error (a slot left empty
/// was skipped after another failed).
fn gather_runs(slots: Vec<Mutex<Option<Result<Vec<RunMetrics>>>>>) -> Result<Vec<RunMetrics>> {
    let mut runs = Vec::new();
    let mut first_error = None;
    for slot in slots {
        match slot.into_inner().ok().flatten() {
            Some(Ok(r)) => runs.extend(r),
            Some(Err(e)) => {
                first_error.get_or_insert(e);
            }
            None => {}
        }
    }
    match first_error {
        Some(e) => Err(e),
        None => Ok(runs),
    }
}

/// Runs the sweep with as many workers as the current rayon pool has threads
/// (wrap it in `pool.install` to choose). `progress` is called as traces
/// finish, from the worker threads.
///
/// # Errors
/// [`Error::InvalidParameter`] for a bad configuration, and whatever the
/// engine or Embree reports.
pub fn run_cornell(
    cfg: &CornellConfig,
    progress: &(dyn Fn(CornellProgress) + Sync),
) -> Result<CornellResults> {
    cfg.validate()?;
    let start = Instant::now();
    let params = AnalysisParams::default();
    let t = Instant::now();
    let mut alpha_ns = cfg.n_values.clone();
    alpha_ns.push(0.0);
    let mut alpha = alpha_rows(&alpha_ns, &params)?;
    let alpha_ref = alpha
        .pop()
        .ok_or_else(|| Error::param("n sweep", "empty"))?;
    let analysis_s = t.elapsed().as_secs_f64();

    let mut scene = sweep_scene(cfg)?;
    let mesh_names: Vec<String> = scene.meshes().iter().map(|m| m.name.clone()).collect();
    let device = Device::pinned_or_default(cfg.embree_isa)?;
    let rt = scene.embree_geometry(&device)?;
    let points = density_points(&scene);
    let total = cfg.run_count();
    let mut timing = mode_timings(&cfg.modes);

    progress(CornellProgress {
        done: 0,
        total,
        n: 0.0,
        mode: Mode::Classic,
    });
    let workers = rayon::current_num_threads().max(1);
    let one_thread = crate::embree::thread_pool(1)?;
    let pools = (0..workers)
        .map(|_| crate::embree::thread_pool(1))
        .collect::<Result<Vec<_>>>()?;
    scene.set_cosn(CosN::new(0.0)?);
    let reference = one_thread.install(|| {
        run_one(
            &Tracer::new(PreparedScene::new(scene.clone(), &rt)?),
            &cfg.trace_config(Mode::Classic),
            0.0,
            &points,
            &mesh_names,
            &alpha_ref,
        )
    })?;
    account(&mut timing, &reference);
    let done = AtomicUsize::new(1);
    let density_cfg = density_config(cfg, &reference);

    // Every run at one n, in mode order, on the calling thread's pool.
    let runs_at = |i: usize| -> Result<Vec<RunMetrics>> {
        let (n, a) = (cfg.n_values[i], &alpha[i]);
        let mut scene = scene.clone();
        scene.set_cosn(CosN::new(n as f32)?);
        let tracer = Tracer::new(PreparedScene::new(scene, &rt)?);
        let mut out = Vec::with_capacity(cfg.modes.len());
        for &mode in &cfg.modes {
            if mode == Mode::Classic && n == 0.0 {
                out.push(reference.clone());
                continue;
            }
            let tc = match mode {
                Mode::Density => density_cfg.clone(),
                m => cfg.trace_config(m),
            };
            out.push(run_one(&tracer, &tc, n, &points, &mesh_names, a)?);
            progress(CornellProgress {
                done: done.fetch_add(1, Ordering::Relaxed) + 1,
                total,
                n,
                mode,
            });
        }
        Ok(out)
    };
    let runs = over_pools(&pools, cfg.n_values.len(), &runs_at)?;
    for r in &runs {
        if !(r.mode == Mode::Classic && r.n == 0.0) {
            account(&mut timing, r);
        }
    }
    let done = done.into_inner();
    progress(CornellProgress {
        done,
        total,
        n: cfg.n_values.last().copied().unwrap_or(0.0),
        mode: cfg.modes.last().copied().unwrap_or(Mode::Classic),
    });
    Ok(CornellResults {
        scene: cfg.scene.clone(),
        n_max: cfg.n_max,
        seed: cfg.seed,
        estimator: cfg.estimator.to_string(),
        max_depth: cfg.max_depth,
        modes: cfg.modes.clone(),
        n_values: cfg.n_values.clone(),
        reference,
        runs,
        alpha,
        analysis_s,
        timing,
        traces: done,
        elapsed_s: start.elapsed().as_secs_f64(),
    })
}
