//! The wave loop: emission (wave 0), then one wave per bounce depth, until the
//! queue is empty or the depth limit is reached.

use super::albedo::AlbedoTable;
use super::buffer::{map_frame, trace_wave};
use super::config::{CheckedConfig, DensityTarget, Mode, TraceConfig, DENSITY_CONTROL_K};
use super::counts::{plan_emission, LightPlan};
use super::density_control::DensityControl;
use super::report::TraceReport;
use super::stream::Schedule;
use super::wave::{BatchOut, PathState, ShadeContext};
use crate::analysis::{AnalysisCache, DirectionalityTable};
use crate::error::{Error, Result};
use crate::importance::ImportanceCounts;
use crate::photon_map::{CompactPhoton, PhotonMap, PhotonRecord, Quantizer};
use crate::raycast::RayCaster;
use crate::sampling::luminance;
use crate::scene::{PreparedScene, Scene};
use rayon::prelude::*;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Instant;

/// An upper bound of the children a wave can make: the sum over its photons of
/// `min(cap, max(alpha_max alpha_E N_MAX, 1)) + 1` (`alpha_D <= 1`, Russian
/// roulette makes at most one child, rounding up adds at most one, and
/// `alpha_max` bounds importance's `alpha_I`: 1 without it). Each term is
/// rounded up to a multiple of 2^-16 and summed as an integer: exact, so the
/// bound does not depend on how the wave is cut into chunks and batches, nor
/// on the thread count.
fn split_bound(
    wave: &[Vec<PathState>],
    max_light_luminance: f32,
    n_max: u64,
    cap: u32,
    alpha_max: f64,
) -> f64 {
    const UNIT: f64 = 65_536.0;
    let units: u128 = wave
        .par_iter()
        .flat_map_iter(|c| c.iter())
        .map(|p| {
            let s = luminance(p.power) as f64 / max_light_luminance as f64 * n_max as f64;
            // At most (cap + 1) 2^16 <= 2^48: exact in a u64. Rounded up
            // without `ceil` (a libm call on baseline x86-64).
            let v = ((s * alpha_max).max(1.0).min(cap as f64) + 1.0) * UNIT;
            let whole = v as u64;
            u128::from(whole + u64::from((whole as f64) < v))
        })
        .sum();
    units as f64 / UNIT
}

/// A material's alpha_D table (`None` outside adaptive mode and for delta BRDFs).
type MaterialTable = Option<Arc<DirectionalityTable>>;

/// alpha_D tables for the materials the scene's meshes use, and their
/// glass parts (adaptive mode only): only what the scene needs is analysed.
fn material_tables(
    scene: &Scene,
    cache: &mut AnalysisCache,
    mode: Mode,
) -> Result<Vec<MaterialTable>> {
    let mut tables = vec![None; scene.materials.len()];
    if mode != Mode::Adaptive {
        return Ok(tables);
    }
    for mesh in &scene.meshes {
        // A partly transmitting material scatters by its glass part too.
        let glass = scene
            .transmission_mix(mesh.material as u32)
            .map(|mix| mix.glass);
        for m in std::iter::once(mesh.material).chain(glass) {
            let brdf = &scene.materials[m].brdf;
            if tables[m].is_none() && !brdf.is_delta() {
                tables[m] = Some(cache.brdf(brdf)?);
            }
        }
    }
    Ok(tables)
}

/// Bytes a stored photon costs: it is written once, compact, into the map
/// buffer, and the kd-tree is built in place over it. The budget is this
/// times the photons stored plus the pending paths (bounded by the waves);
/// `Error::Budget` when the emitted photons alone would not fit.
pub const BYTES_PER_STORED_PHOTON: u64 = std::mem::size_of::<CompactPhoton>() as u64;

/// Where a trace is, for a progress bar.
#[derive(Clone, Copy, Debug)]
pub struct TraceProgress {
    /// Bounce depth of the wave under way (0 = photons leaving the lights).
    pub depth: u32,
    /// Photons emitted so far (waves are streamed depth by depth).
    pub done: u64,
    /// Photons the run emits.
    pub total: u64,
}

/// The photons of a run and what it counted.
#[derive(Clone, Debug)]
pub struct TraceOutput {
    /// Every stored photon, compact, in `frame` (in an order that depends on
    /// the batch size; the kd-tree built over them does not).
    pub photons: Vec<CompactPhoton>,
    /// The frame the photons are encoded in ([`map_frame`]).
    pub frame: Quantizer,
    /// Counts and timings.
    pub report: TraceReport,
    /// Per-light emission.
    pub plans: Vec<LightPlan>,
}

impl TraceOutput {
    /// The stored photons, decoded (positions and powers as quantised).
    pub fn records(&self) -> Vec<PhotonRecord> {
        self.photons
            .par_iter()
            .with_min_len(4096)
            .map(|p| self.frame.decode(p))
            .collect()
    }

    /// The photon map of every stored photon, built in place (no copy).
    pub fn into_map(self) -> PhotonMap {
        PhotonMap::from_compact(self.photons, self.frame)
    }
}

/// Traces photons through one prepared scene (a [`Scene`] and the
/// [`RayCaster`] built from it); keeps the directionality analyses between
/// runs (each emission profile and BRDF is analysed once).
///
/// A tracer owns what it needs (`'static` when the caster is): store it in
/// your own struct, share it between threads (`trace` takes `&self`; runs
/// on several threads at once share the analysis cache).
pub struct Tracer<C> {
    prepared: Arc<PreparedScene<C>>,
    cache: Mutex<Option<AnalysisCache>>,
}

impl<C> std::fmt::Debug for Tracer<C> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Tracer")
            .field("meshes", &self.prepared.scene().meshes.len())
            .field("lights", &self.prepared.scene().lights.len())
            .finish_non_exhaustive()
    }
}

impl<C: RayCaster> Tracer<C> {
    /// A tracer for a prepared scene (from `Scene::commit` with Embree, or
    /// [`PreparedScene::new`] with a caster of your own); pass it by value or
    /// as an `Arc` to share it.
    pub fn new(prepared: impl Into<Arc<PreparedScene<C>>>) -> Self {
        Tracer {
            prepared: prepared.into(),
            cache: Mutex::new(None),
        }
    }

    /// Starts from analyses done before (by another tracer, or loaded): runs
    /// whose analysis settings match it reuse them.
    pub fn with_cache(self, cache: AnalysisCache) -> Self {
        Tracer {
            cache: Mutex::new(Some(cache)),
            ..self
        }
    }

    /// The scene traced.
    pub fn scene(&self) -> &Scene {
        self.prepared.scene()
    }

    /// The prepared scene (scene and caster).
    pub fn prepared(&self) -> &Arc<PreparedScene<C>> {
        &self.prepared
    }

    /// A copy of the analyses done so far (`None` before the first run).
    pub fn analysis_cache(&self) -> Option<AnalysisCache> {
        self.lock_cache().clone()
    }

    fn lock_cache(&self) -> std::sync::MutexGuard<'_, Option<AnalysisCache>> {
        // A panic while analysing leaves a cache that is still consistent
        // (entries are inserted whole), so a poisoned lock is taken as is.
        self.cache.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Traces one run on the current rayon pool.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for bad settings, [`Error::InvalidScene`] for a
    /// scene without light or a hit on a material the scene does not have,
    /// [`Error::Budget`] when the emitted photons alone would not fit in the
    /// memory budget (Q = 1 on any real machine), [`Error::OutOfMemory`]
    /// when the system refuses memory the budget allows.
    pub fn trace(&self, cfg: &TraceConfig) -> Result<TraceOutput> {
        self.trace_checked(&cfg.check()?, &|_| {})
    }

    /// [`Tracer::trace`] with a progress callback, called from worker threads.
    ///
    /// # Errors
    /// As [`Tracer::trace`].
    pub fn trace_with_progress(
        &self,
        cfg: &TraceConfig,
        progress: &(dyn Fn(TraceProgress) + Sync),
    ) -> Result<TraceOutput> {
        self.trace_checked(&cfg.check()?, progress)
    }

    /// Emission plans and the alpha_D tables of the run, from the cache
    /// (held only while analysing).
    fn analyse(&self, cfg: &CheckedConfig) -> Result<(Vec<LightPlan>, Vec<MaterialTable>)> {
        let mut guard = self.lock_cache();
        let stale = guard
            .as_ref()
            .is_none_or(|c| c.params() != cfg.analysis() || c.estimator() != cfg.estimator());
        if stale {
            *guard = Some(AnalysisCache::new(*cfg.analysis(), cfg.estimator())?);
        }
        let Some(cache) = guard.as_mut() else {
            unreachable!("set just above")
        };
        let plans = plan_emission(self.scene(), cfg.mode(), cfg.n_max(), cache)?;
        let tables = material_tables(self.scene(), cache, cfg.mode())?;
        Ok((plans, tables))
    }

    /// [`Tracer::trace_with_progress`] with settings checked beforehand.
    ///
    /// # Errors
    /// As [`Tracer::trace`].
    pub fn trace_checked(
        &self,
        cfg: &CheckedConfig,
        progress: &(dyn Fn(TraceProgress) + Sync),
    ) -> Result<TraceOutput> {
        // Checked once, when it was prepared.
        let scene = self.prepared.scene();
        let (mut plans, tables) = self.analyse(cfg)?;
        let importance = match &cfg.settings().importance {
            Some(ic) => Some(crate::importance::counts::prepare(
                &self.prepared,
                ic,
                cfg.seed(),
                &mut plans,
            )?),
            None => None,
        };
        let n_max = cfg.n_max();
        let shard = cfg.settings().shard;
        let emitted = emitted_within_budget(&plans, cfg)?;
        let budget_bytes = cfg.memory_budget();
        let max_photons = budget_bytes / BYTES_PER_STORED_PHOTON;
        let albedo: Vec<AlbedoTable> = scene
            .materials
            .iter()
            .map(|m| AlbedoTable::new(&m.brdf))
            .collect();
        let epsilon = scene.ray_epsilon();
        let max_light_luminance = scene
            .lights
            .iter()
            .map(|l| luminance(l.power()))
            .fold(0.0f32, f32::max);

        let kernels = self.prepared.caster().kernels();
        let mut report = TraceReport::new(cfg.mode(), n_max, &plans, kernels);
        report.importance = importance.as_ref().map(|(_, r)| r.clone());
        // alpha_I multiplies a hit's children by up to ALPHA_I_MAX (1, exactly,
        // without importance: the paper's bound bit for bit).
        let alpha_max = match &importance {
            Some(_) => f64::from(crate::importance::ALPHA_I_MAX),
            None => 1.0,
        };
        let frame = map_frame(scene, &plans);
        let start = Instant::now();
        let mut density = density_control(scene, cfg, emitted, &frame)?;
        // The map buffer, reserved for what a diffuse scene typically
        // stores (about 2-3 hits per emitted photon) and grown when needed up
        // to the budget: a large buffer grows by mremap in glibc, without a
        // copy. An allocation the OS refuses is `Error::OutOfMemory`, not an abort.
        let mut photons: Vec<CompactPhoton> = Vec::new();
        if density.is_none() {
            let guess = emitted.saturating_mul(3).min(max_photons) as usize;
            reserve(&mut photons, guess, budget_bytes)?;
        }
        let mut schedule = Schedule::new(emitted, cfg.max_depth(), density.is_some(), shard);
        let mut wave: Vec<Vec<PathState>> = Vec::new();
        let mut splitting = cfg.mode() == Mode::Adaptive;
        // What the run holds, in stored photons' worth of memory: the buffer
        // and the pending paths (a path is three photons' worth).
        let path_cost =
            (std::mem::size_of::<PathState>() / BYTES_PER_STORED_PHOTON as usize) as u64;
        while let Some(depth) = schedule.next_wave(scene, &plans, cfg.seed(), epsilon, &mut wave) {
            let wave_start = Instant::now();
            let wave_len: usize = wave.iter().map(Vec::len).sum();
            let held = |photons: usize, pending: usize| photons as u64 + pending as u64 * path_cost;
            let stored_so_far =
                photons.len() + density.as_ref().map_or(0, |d| d.counts().0 as usize);
            let used = held(stored_so_far, schedule.pending_len() + wave_len);
            // Splitting stops once the run holds half the budget; the rest
            // of the run is then classic Russian roulette.
            if splitting && used * 2 > max_photons {
                splitting = false;
                report.budget_bound = true;
            }
            let split_scale = if splitting {
                let room = ((max_photons / 2).saturating_sub(used) / (path_cost + 1)) as f64;
                let bound = split_bound(
                    &wave,
                    max_light_luminance,
                    n_max,
                    cfg.split_cap(),
                    alpha_max,
                );
                wave_split_scale(room, bound, &mut report)
            } else {
                1.0
            };
            if density.is_none() && !room_for_wave(&mut photons, wave_len, budget_bytes)? {
                report.budget_bound = true;
                break;
            }
            let ctx = ShadeContext {
                scene,
                caster: self.prepared.caster(),
                tables: &tables,
                albedo: &albedo,
                alpha_min: cfg.analysis().alpha_min,
                max_light_luminance,
                n_max_refl: if splitting {
                    n_max as f64 * split_scale
                } else {
                    0.0
                },
                split_cap: cfg.split_cap(),
                continue_paths: depth < cfg.max_depth() as usize,
                keep_records: density.is_some(),
                caustic_only: false,
                frame,
                epsilon,
                depth: depth as u8,
                importance: importance
                    .as_ref()
                    .map(|(g, r)| ImportanceCounts::new(g, r.reference_adjoint)),
            };
            let outs = trace_wave(&ctx, &wave, &mut photons, cfg.batch(), density.is_some());
            absorb_wave(scene, outs, depth, &mut report, &mut density, &mut schedule)?;
            report.depth_mut(depth).seconds += wave_start.elapsed().as_secs_f64();
            progress(TraceProgress {
                depth: depth as u32,
                done: schedule.emitted_so_far(),
                total: emitted,
            });
        }
        if let Some(dc) = density {
            photons = density_photons(dc, &frame, &mut report);
        }
        // Give back the reserved room never used (a large buffer shrinks in
        // place: glibc's realloc of an mmap'd block is an mremap, no copy).
        photons.shrink_to_fit();
        report.trace_s = start.elapsed().as_secs_f64();
        report.finish(&frame.power_sums(&photons));
        Ok(TraceOutput {
            photons,
            frame,
            report,
            plans,
        })
    }
}

/// Reserves room for `more` photons (within the budget: checked by the
/// callers), or says the system refused it.
/// The photons this shard emits, refused when they alone would not fit in
/// the memory budget. Checked: two lights of ~2^63 photons each overflowed
/// u64. The budget is per shard: only this shard's photons are traced.
fn emitted_within_budget(plans: &[LightPlan], cfg: &CheckedConfig) -> Result<u64> {
    let shard = cfg.settings().shard;
    let emitted: u64 = plans
        .iter()
        .try_fold(0u64, |a, p| a.checked_add(shard.len_of(p.photons)))
        .unwrap_or(u64::MAX);
    let budget_bytes = cfg.memory_budget();
    if emitted > budget_bytes / BYTES_PER_STORED_PHOTON {
        return Err(Error::Budget {
            photons: emitted,
            needed_bytes: emitted.saturating_mul(BYTES_PER_STORED_PHOTON),
            budget_bytes,
        });
    }
    Ok(emitted)
}

/// Density control's grid, in density mode when anything is emitted.
fn density_control(
    scene: &Scene,
    cfg: &CheckedConfig,
    emitted: u64,
    frame: &Quantizer,
) -> Result<Option<DensityControl>> {
    if cfg.mode() != Mode::Density || emitted == 0 {
        return Ok(None);
    }
    let target = match cfg.density_target() {
        DensityTarget::PerArea(d) => d,
        DensityTarget::Auto => {
            cfg.n_max() as f64 / scene.surface_sampler().total_area().max(f64::MIN_POSITIVE)
        }
    };
    Ok(Some(
        DensityControl::new(scene.bounds(), target, DENSITY_CONTROL_K)?
            .with_power_cap(frame.power_scale() as f32),
    ))
}

/// The factor on every `s` of a wave. Its children must fit in what is left
/// of half the budget (`room`, in paths), or one wave of splitting alone
/// could exhaust memory (a sharp light at a high Q: few photons, each split
/// many times). `s <= alpha_E(photon) N_MAX` (alpha_D <= 1), so `bound`, the
/// sum of that over the wave, caps the children; when it exceeds the room
/// left, every `s` of the wave is scaled down to fit.
fn wave_split_scale(room: f64, bound: f64, report: &mut TraceReport) -> f64 {
    if bound > room {
        report.budget_bound = true;
        room / bound
    } else {
        1.0
    }
}

/// A traced wave's counts into the report, its records offered to density
/// control, its children queued for the next depth; a hit on a material the
/// scene lacks (a user's caster) is an error.
fn absorb_wave(
    scene: &Scene,
    outs: Vec<BatchOut>,
    depth: usize,
    report: &mut TraceReport,
    density: &mut Option<DensityControl>,
    schedule: &mut Schedule,
) -> Result<()> {
    if let Some(bad) = outs.iter().find_map(|o| o.bad_hit) {
        return Err(bad.into_error(scene));
    }
    let mut report_importance = report.importance.take();
    let stats = report.depth_mut(depth);
    for out in outs {
        stats.hits += out.hits;
        stats.escaped += out.escaped;
        stats.capped += out.capped;
        if let Some(imp) = report_importance.as_mut() {
            imp.unread += out.unread;
        }
        stats.children += out.children.len() as u64;
        if let Some(dc) = density {
            dc.offer(&out.records, &out.normals);
        }
        schedule.pending[depth + 1].push_chunk(out.children);
    }
    report.importance = report_importance;
    Ok(())
}

/// Density control's accepted records, encoded (non-finite ones dropped),
/// with its counts in the report.
fn density_photons(
    dc: DensityControl,
    frame: &Quantizer,
    report: &mut TraceReport,
) -> Vec<CompactPhoton> {
    let (accepted, rejected) = dc.counts();
    report.density_rejected = rejected;
    report.density_accepted = accepted;
    dc.into_records()
        .par_iter()
        .with_min_len(4096)
        .filter(|r| r.position.is_finite() && r.power.is_finite())
        .map(|r| frame.encode(r))
        .collect()
}

/// Every photon of a wave may store once: grows the buffer to hold
/// `wave_len` more, or says `false` when that would overflow the budget
/// (the run stops before it could).
fn room_for_wave(
    photons: &mut Vec<CompactPhoton>,
    wave_len: usize,
    budget_bytes: u64,
) -> Result<bool> {
    let max_photons = budget_bytes / BYTES_PER_STORED_PHOTON;
    if photons.len() + wave_len <= photons.capacity() {
        return Ok(true);
    }
    if (photons.len() + wave_len) as u64 > max_photons {
        return Ok(false);
    }
    let more =
        (photons.capacity().max(wave_len) as u64).min(max_photons - photons.len() as u64) as usize;
    reserve(photons, more, budget_bytes)?;
    Ok(true)
}

fn reserve(photons: &mut Vec<CompactPhoton>, more: usize, budget_bytes: u64) -> Result<()> {
    photons
        .try_reserve_exact(more)
        .map_err(|_| Error::OutOfMemory {
            what: "the photon map",
            bytes: (photons.len() + more) as u64 * BYTES_PER_STORED_PHOTON,
            budget_bytes,
        })
}
