//! The wave loop: emission (wave 0), then one wave per bounce depth, until the
//! queue is empty or the depth limit is reached.

use super::albedo::AlbedoTable;
use super::config::{available_memory, DensityTarget, Mode, TraceConfig, DENSITY_CONTROL_K};
use super::counts::{photon_power, plan_emission, LightPlan};
use super::density_control::DensityControl;
use super::report::TraceReport;
use super::wave::{shade_batch, BatchOut, PathState, ShadeContext};
use crate::analysis::{AnalysisCache, DirectionalityTable};
use crate::embree::CommittedScene;
use crate::error::{Error, Result};
use crate::photon_map::PhotonRecord;
use crate::rng::{hash2, Rng};
use crate::sampling::luminance;
use crate::scene::Scene;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Instant;

/// An upper bound of the children a wave can make: the sum over its photons of
/// `min(cap, max(alpha_E N_MAX, 1)) + 1` (`alpha_D <= 1`, Russian roulette
/// makes at most one child, and rounding up adds at most one). Summed in
/// fixed chunks, in order, so it does not depend on the thread count or the
/// batch size.
fn split_bound(queue: &[PathState], max_light_luminance: f32, n_max: u64, cap: u32) -> f64 {
    const CHUNK: usize = 4096;
    let per_chunk: Vec<f64> = queue
        .par_chunks(CHUNK)
        .map(|c| {
            c.iter()
                .map(|p| {
                    let s = luminance(p.power) as f64 / max_light_luminance as f64 * n_max as f64;
                    s.max(1.0).min(cap as f64) + 1.0
                })
                .sum::<f64>()
        })
        .collect();
    per_chunk.iter().sum()
}

/// alpha_D tables for the materials the scene's meshes use (adaptive mode
/// only): only what the scene needs is analysed.
fn material_tables(
    scene: &Scene,
    cache: &mut AnalysisCache,
    mode: Mode,
) -> Result<Vec<Option<Arc<DirectionalityTable>>>> {
    let mut tables = vec![None; scene.materials.len()];
    if mode != Mode::Adaptive {
        return Ok(tables);
    }
    for mesh in &scene.meshes {
        let m = mesh.material;
        let brdf = &scene.materials[m].brdf;
        if tables[m].is_none() && !brdf.is_delta() {
            tables[m] = Some(cache.brdf(brdf)?);
        }
    }
    Ok(tables)
}

/// Bytes one photon costs while a run is under way: its record, its queue
/// entry, and its compact copy in the final map. Used to turn the memory
/// budget into a photon count before anything is allocated.
pub const BYTES_PER_PHOTON_IN_FLIGHT: u64 =
    (std::mem::size_of::<PhotonRecord>() + std::mem::size_of::<PathState>() + 16) as u64;

/// Progress of a run, for a progress bar.
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    /// Bounce depth of the wave under way (0 = photons leaving the lights).
    pub depth: u32,
    /// Photons of this wave traced so far.
    pub done: u64,
    /// Photons in this wave.
    pub total: u64,
}

/// The photons of a run and what it counted.
#[derive(Clone, Debug)]
pub struct TraceOutput {
    /// Every stored photon, tagged with its depth, in a deterministic order.
    pub records: Vec<PhotonRecord>,
    /// Counts and timings.
    pub report: TraceReport,
    /// Per-light emission.
    pub plans: Vec<LightPlan>,
}

/// Traces photons through one scene; keeps the directionality analyses
/// between runs (each emission profile and BRDF is analysed once).
pub struct Tracer<'s> {
    scene: &'s Scene,
    rt: &'s CommittedScene,
    cache: Option<AnalysisCache>,
}

impl<'s> Tracer<'s> {
    /// A tracer for `scene`, whose Embree geometry is `rt` (from [`Scene::commit`]).
    pub fn new(scene: &'s Scene, rt: &'s CommittedScene) -> Self {
        Tracer {
            scene,
            rt,
            cache: None,
        }
    }

    /// The analyses done so far (`None` before the first run).
    pub fn analysis_cache(&self) -> Option<&AnalysisCache> {
        self.cache.as_ref()
    }

    /// Traces one run on the current rayon pool.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for bad settings, [`Error::InvalidScene`] for a
    /// scene without light, [`Error::Budget`] when the emitted photons alone
    /// would not fit in the memory budget (Q = 1 on any real machine).
    pub fn trace(&mut self, cfg: &TraceConfig) -> Result<TraceOutput> {
        self.trace_with_progress(cfg, &|_| {})
    }

    /// [`Tracer::trace`] with a progress callback, called from worker threads.
    ///
    /// # Errors
    /// As [`Tracer::trace`].
    pub fn trace_with_progress(
        &mut self,
        cfg: &TraceConfig,
        progress: &(dyn Fn(Progress) + Sync),
    ) -> Result<TraceOutput> {
        cfg.validate()?;
        self.scene.validate()?;
        let stale = self
            .cache
            .as_ref()
            .is_none_or(|c| c.params() != &cfg.analysis || c.estimator() != cfg.estimator);
        if stale {
            self.cache = Some(AnalysisCache::new(cfg.analysis, cfg.estimator)?);
        }
        let Some(cache) = self.cache.as_mut() else {
            unreachable!("set just above")
        };
        let n_max = cfg.budget.n_max()?;
        let plans = plan_emission(self.scene, cfg.mode, n_max, cache)?;
        // The budget is per shard: only this shard's photons are traced.
        let emitted: u64 = plans.iter().map(|p| cfg.shard.len_of(p.photons)).sum();
        let budget_bytes = cfg.memory_budget.unwrap_or_else(|| available_memory() / 2);
        let max_photons = budget_bytes / BYTES_PER_PHOTON_IN_FLIGHT;
        if emitted > max_photons {
            return Err(Error::Budget {
                photons: emitted,
                needed_bytes: emitted.saturating_mul(BYTES_PER_PHOTON_IN_FLIGHT),
                budget_bytes,
            });
        }
        let tables = material_tables(self.scene, cache, cfg.mode)?;
        let albedo: Vec<AlbedoTable> = self
            .scene
            .materials
            .iter()
            .map(|m| AlbedoTable::new(&m.brdf))
            .collect();
        let (lo, hi) = self.scene.bounds();
        let epsilon = 1e-5 * (hi - lo).length().max(1e-3);
        let max_light_luminance = self
            .scene
            .lights
            .iter()
            .map(|l| luminance(l.power()))
            .fold(0.0f32, f32::max);

        let mut report = TraceReport::new(cfg.mode, n_max, &plans);
        let start = Instant::now();
        let mut queue = self.emit(cfg, &plans, epsilon);
        // Room for what a diffuse scene typically stores (about 3 hits per
        // emitted photon), so the first waves do not copy the array as it grows.
        let mut records: Vec<PhotonRecord> =
            Vec::with_capacity((emitted.saturating_mul(3)).min(max_photons) as usize);
        let mut density = match cfg.mode {
            Mode::Density if emitted > 0 => {
                let target = match cfg.density_target {
                    DensityTarget::PerArea(d) => d,
                    DensityTarget::Auto => {
                        n_max as f64
                            / self
                                .scene
                                .surface_sampler()
                                .total_area()
                                .max(f64::MIN_POSITIVE)
                    }
                };
                Some(DensityControl::new(
                    self.scene.bounds(),
                    target,
                    DENSITY_CONTROL_K,
                )?)
            }
            _ => None,
        };
        let mut splitting = cfg.mode == Mode::Adaptive;
        for depth in 0..=cfg.max_depth {
            if queue.is_empty() {
                break;
            }
            let wave_start = Instant::now();
            // Splitting stops once the photons so far fill half the budget; the
            // rest of the run is then classic Russian roulette.
            if splitting && (records.len() + queue.len()) as u64 * 2 > max_photons {
                splitting = false;
                report.budget_bound = true;
            }
            // The children of this wave must fit in what is left of that half
            // too, or one wave of splitting alone could exhaust memory (a
            // sharp light at a high Q: few photons, each split many times).
            // `s <= alpha_E(photon) N_MAX` (alpha_D <= 1), so the sum of that
            // bound over the queue caps the children; when it exceeds the
            // room left, every `s` of this wave is scaled down to fit.
            let mut split_scale = 1.0;
            if splitting {
                let room =
                    (max_photons / 2).saturating_sub((records.len() + queue.len()) as u64) as f64;
                let bound = split_bound(&queue, max_light_luminance, n_max, cfg.split_cap);
                if bound > room {
                    split_scale = room / bound;
                    report.budget_bound = true;
                }
            }
            let ctx = ShadeContext {
                scene: self.scene,
                rt: self.rt,
                tables: &tables,
                albedo: &albedo,
                alpha_min: cfg.analysis.alpha_min,
                max_light_luminance,
                n_max_refl: if splitting {
                    n_max as f64 * split_scale
                } else {
                    0.0
                },
                split_cap: cfg.split_cap,
                continue_paths: depth < cfg.max_depth,
                keep_normals: cfg.mode == Mode::Density,
                epsilon,
                depth: depth as u8,
            };
            let done = AtomicU64::new(0);
            let total = queue.len() as u64;
            let outs: Vec<BatchOut> = queue
                .par_chunks(cfg.batch)
                .map(|batch| {
                    let out = shade_batch(&ctx, batch);
                    let d =
                        done.fetch_add(batch.len() as u64, Ordering::Relaxed) + batch.len() as u64;
                    progress(Progress {
                        depth,
                        done: d,
                        total,
                    });
                    out
                })
                .collect();
            drop(queue);
            let stored_here: usize = outs.iter().map(|o| o.stored.len()).sum();
            if (records.len() + stored_here) as u64 > max_photons {
                report.budget_bound = true;
                break;
            }
            let mut next: Vec<PathState> =
                Vec::with_capacity(outs.iter().map(|o| o.children.len()).sum());

            let stats = report.depth_mut(depth as usize);
            for out in outs {
                stats.hits += out.hits;
                stats.escaped += out.escaped;
                stats.capped += out.capped;
                stats.children += out.children.len() as u64;
                match &mut density {
                    Some(dc) => dc.offer(&out.stored, &out.normals),
                    None => records.extend_from_slice(&out.stored),
                }
                next.extend_from_slice(&out.children);
            }
            stats.seconds = wave_start.elapsed().as_secs_f64();
            queue = next;
        }
        if let Some(dc) = density {
            let (accepted, rejected) = dc.counts();
            report.density_rejected = rejected;
            report.density_accepted = accepted;
            records = dc.into_records();
        }
        report.trace_s = start.elapsed().as_secs_f64();
        report.finish(&records);
        Ok(TraceOutput {
            records,
            report,
            plans,
        })
    }

    /// Wave 0: every light's photons (of `cfg.shard`), photon `i` of light `l` keyed by (seed, l, i).
    fn emit(&self, cfg: &TraceConfig, plans: &[LightPlan], epsilon: f32) -> Vec<PathState> {
        let total: u64 = plans.iter().map(|p| cfg.shard.len_of(p.photons)).sum();
        let mut queue = Vec::with_capacity(total as usize);
        for (l, (light, plan)) in self.scene.lights.iter().zip(plans).enumerate() {
            let power = photon_power(light, plan);
            let light_key = hash2(cfg.seed, l as u64);
            // Indexed: par_extend keeps photon i at position start + i.
            // A shard emits its own ids only (`Shard::range`); their keys are unchanged.
            queue.par_extend(cfg.shard.range(plan.photons).into_par_iter().map(|i| {
                let key = hash2(light_key, i);
                let mut rng = Rng::new(key);
                let e = light.sample(rng.next_f32(), rng.next_2d(), rng.next_2d());
                PathState {
                    origin: e.origin + e.normal.unwrap_or_default() * epsilon,
                    direction: e.direction,
                    power: power * e.weight,
                    key,
                }
            }));
        }
        queue
    }
}
