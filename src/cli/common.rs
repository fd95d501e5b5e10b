//! Arguments and helpers shared by the subcommands.

use adaptive_pm::analysis::Estimator;
use adaptive_pm::emitter::CosN;
use adaptive_pm::engine::config::{DEFAULT_MAX_DEPTH, DEFAULT_SPLIT_CAP};
use adaptive_pm::engine::{Budget, Mode, TraceConfig};
use adaptive_pm::scene::Scene;
use anyhow::Context;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;

/// The photon budget and the settings of a run.
#[derive(clap::Args, Debug, Clone)]
pub struct BudgetArgs {
    /// Quality Q in [0, 1]: N_MAX = Q^2 * (2^31 - 1).
    #[arg(long, short = 'q', conflicts_with = "n_max")]
    pub quality: Option<f64>,
    /// N_MAX directly (default 100000, the paper's experiments).
    #[arg(long, short = 'n')]
    pub n_max: Option<u64>,
    /// Override every area light's cos^n exponent.
    #[arg(long, allow_negative_numbers = true)]
    pub cosn: Option<f32>,
    /// Seed of every random number.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Bounces after the first hit.
    #[arg(long, default_value_t = DEFAULT_MAX_DEPTH)]
    pub max_depth: u32,
    /// Per-hit cap on children (adaptive mode).
    #[arg(long, default_value_t = DEFAULT_SPLIT_CAP)]
    pub split_cap: u32,
    /// Memory for photons in MiB (default: half the available memory).
    #[arg(long)]
    pub budget_mb: Option<u64>,
    /// Directionality estimator: paper (the paper's clustering) or peak (peak density).
    #[arg(long, default_value = "paper", value_parser = parse_estimator)]
    pub directionality: Estimator,
}

pub fn parse_estimator(s: &str) -> Result<Estimator, String> {
    s.parse().map_err(|e: adaptive_pm::Error| e.to_string())
}

impl BudgetArgs {
    pub fn config(&self, mode: Mode) -> anyhow::Result<TraceConfig> {
        let budget = match (self.quality, self.n_max) {
            (Some(q), _) => Budget::Quality(q),
            (None, Some(n)) => Budget::NMax(n),
            (None, None) => Budget::NMax(100_000),
        };
        let mut cfg = TraceConfig::new(mode, budget);
        cfg.seed = self.seed;
        cfg.max_depth = self.max_depth;
        cfg.split_cap = self.split_cap;
        cfg.memory_budget = self.budget_mb.map(|mb| mb << 20);
        cfg.estimator = self.directionality;
        cfg.validate()?;
        Ok(cfg)
    }
}

/// Thread count.
#[derive(clap::Args, Debug, Clone)]
pub struct ThreadArgs {
    /// Worker threads (0 = all cores).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
}

impl ThreadArgs {
    pub fn pool(&self) -> anyhow::Result<rayon::ThreadPool> {
        Ok(adaptive_pm::embree::thread_pool(self.threads)?)
    }
}

/// Opens a scene by name or path, with an optional cos^n override.
pub fn open_scene(name: &str, cosn: Option<f32>) -> anyhow::Result<Scene> {
    let mut scene = Scene::open(name).with_context(|| format!("scene `{name}`"))?;
    if let Some(n) = cosn {
        scene.set_cosn(CosN::new(n)?);
    }
    scene.validate()?;
    Ok(scene)
}

/// A progress bar on a terminal's stderr; hidden otherwise or when `show` is false.
pub fn progress_bar(show: bool) -> ProgressBar {
    if !show || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(0), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template("{spinner} {msg:>10} [{bar:40}] {pos}/{len} photons ({eta})")
            .expect("static template")
            .progress_chars("=> "),
    );
    bar
}
