//! `trace --shard I/N --out FILE.apm`: which shard a process traces (from the
//! flag or from the scheduler's environment) and writing its photon file.

use adaptive_pm::engine::counts::LightPlan;
use adaptive_pm::engine::report::TraceReport;
use adaptive_pm::engine::{Shard, TraceConfig};
use adaptive_pm::output::{probe, refuse_overwrite};
use adaptive_pm::photon_file::{
    canonical_frame, photons_checksum, scene_hash, write_photons, ShardInfo,
};
use adaptive_pm::photon_map::PhotonMap;
use adaptive_pm::scene::Scene;
use anyhow::{bail, Context};
use std::path::{Path, PathBuf};

/// Sharding arguments of `trace`.
#[derive(clap::Args, Debug, Clone)]
pub struct ShardArgs {
    /// Trace shard I of N (0-based, e.g. 3/8) and write it with --out. Without
    /// it, --out takes I and N from SLURM_ARRAY_TASK_ID (minus
    /// SLURM_ARRAY_TASK_MIN, over SLURM_ARRAY_TASK_STEP) and
    /// SLURM_ARRAY_TASK_COUNT, or from JOB_COMPLETION_INDEX and --shards.
    #[arg(long, conflicts_with = "shards")]
    pub shard: Option<Shard>,
    /// Shard count N for a Kubernetes Indexed Job (JOB_COMPLETION_INDEX), or a
    /// check of SLURM_ARRAY_TASK_COUNT in a Slurm array.
    #[arg(long)]
    pub shards: Option<u32>,
    /// Write the run's photons to this photon file (.apm; docs/photon-file.md).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// An environment variable as a number, `None` when unset.
fn env_u32(name: &str) -> anyhow::Result<Option<u32>> {
    match std::env::var(name) {
        Ok(v) => Ok(Some(v.trim().parse().with_context(|| {
            format!("{name}={v:?} is not a non-negative integer")
        })?)),
        Err(std::env::VarError::NotPresent) => Ok(None),
        Err(e) => Err(e).with_context(|| format!("reading {name}")),
    }
}

impl ShardArgs {
    /// The shard this process traces: --shard, else (with --out) the scheduler's
    /// environment, else the whole run.
    pub fn resolve(&self) -> anyhow::Result<Shard> {
        if let Some(s) = self.shard {
            if self.out.is_none() {
                bail!("--shard needs --out FILE.apm: a shard's photons are only useful merged");
            }
            return Ok(s);
        }
        if self.out.is_none() {
            if self.shards.is_some() {
                bail!("--shards needs --out FILE.apm");
            }
            return Ok(Shard::WHOLE);
        }
        if let Some(id) = env_u32("SLURM_ARRAY_TASK_ID")? {
            let min = env_u32("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
            let step = env_u32("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1).max(1);
            let Some(count) = env_u32("SLURM_ARRAY_TASK_COUNT")?.or(self.shards) else {
                bail!("SLURM_ARRAY_TASK_ID is set but not SLURM_ARRAY_TASK_COUNT: pass --shards N");
            };
            if let Some(n) = self.shards.filter(|&n| n != count) {
                bail!("--shards {n} but the Slurm array has {count} tasks");
            }
            if id < min || (id - min) % step != 0 {
                bail!("SLURM_ARRAY_TASK_ID={id} is not in the array {min}..:{step}");
            }
            return Ok(Shard::new((id - min) / step, count)?);
        }
        if let Some(i) = env_u32("JOB_COMPLETION_INDEX")? {
            let Some(n) = self.shards else {
                bail!("JOB_COMPLETION_INDEX is set: pass the job's completions as --shards N");
            };
            return Ok(Shard::new(i, n)?);
        }
        if let Some(n) = self.shards {
            bail!("--shards {n} without SLURM_ARRAY_TASK_ID or JOB_COMPLETION_INDEX: use --shard I/{n}");
        }
        Ok(Shard::WHOLE)
    }
}

impl ShardArgs {
    /// Checks `--out`, if given, before the scene is even loaded: it must
    /// not name the scene file (`trace x.gltf --out x.gltf` replaced the
    /// scene), its folder must exist and be writable, and it must not be a
    /// folder or a device. A long trace then never ends in "cannot write".
    pub fn check_out(&self, scene: &Path) -> anyhow::Result<()> {
        let Some(out) = &self.out else {
            return Ok(());
        };
        // A built-in scene's name is no file: compare only a path that exists.
        let inputs: &[&Path] = if scene.exists() { &[scene] } else { &[] };
        refuse_overwrite(out, inputs).context("--out")?;
        probe(out).context("--out")?;
        Ok(())
    }
}

/// The run's checksum (`trace --json`'s `checksum`) and, with `--out`, its photon file.
pub fn checksum_and_write(
    args: &ShardArgs,
    scene: &Scene,
    cfg: &TraceConfig,
    map: &PhotonMap,
    (report, plans): (&TraceReport, &[LightPlan]),
) -> anyhow::Result<u64> {
    let frame = canonical_frame(scene, plans);
    // The tracer wrote its photons in this frame: the map's must be it.
    anyhow::ensure!(
        frame.matches(map.quantizer()),
        "internal: the map's frame is not the run's canonical frame"
    );
    let checksum = photons_checksum(map.compact_photons(), map.quantizer());
    if let Some(path) = &args.out {
        let info = ShardInfo {
            scene_hash: scene_hash(scene),
            frame,
            emitted: plans
                .iter()
                .fold(0u64, |a, p| a.saturating_add(cfg.shard.len_of(p.photons))),
            emitted_total: plans.iter().fold(0u64, |a, p| a.saturating_add(p.photons)),
            budget_bound: report.budget_bound,
            kernels: report.kernels,
            math: report.math,
        };
        let header = write_photons(path, cfg, &info, map.compact_photons())?;
        debug_assert_eq!(header.map_checksum, checksum);
    }
    Ok(checksum)
}
