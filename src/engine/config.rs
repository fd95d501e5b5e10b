//! What a run is asked to do: the mode, the photon budget (Q or N_MAX), the
//! bounds on splitting and on memory, and the seed.

use super::shard::Shard;
use crate::analysis::{AnalysisParams, Estimator};
use crate::error::{Error, Result};

/// `INT_MAX` of the paper's `N_MAX = Q^2 * INT_MAX`.
pub const INT_MAX: u64 = i32::MAX as u64;

/// Default bounce limit: deep enough that a white box keeps < 1 % of its power
/// (0.73^15 ~ 0.9 %), shallow enough to bound albedo-1 scenes.
pub const DEFAULT_MAX_DEPTH: u32 = 15;

/// Default per-hit cap on children: a photon never splits into more than this.
pub const DEFAULT_SPLIT_CAP: u32 = 4096;

/// How many nearest photons the density-control acceptance test looks at
/// (RenderPark's value).
pub const DENSITY_CONTROL_K: usize = 20;

/// The three ways of tracing compared in every experiment (docs/method.md,
/// "The three modes").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Markov chains: `N_MAX` photons shared by power, Russian roulette, no splitting.
    Classic,
    /// Classic emission; a photon is stored only where the map is sparser than a target.
    Density,
    /// The paper's counts and splitting.
    Adaptive,
}

impl Mode {
    /// All modes, in the order experiments report them.
    pub const ALL: [Mode; 3] = [Mode::Classic, Mode::Density, Mode::Adaptive];

    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Classic => "classic",
            Mode::Density => "density",
            Mode::Adaptive => "adaptive",
        }
    }
}

impl std::fmt::Display for Mode {
    /// [`Mode::name`]: what `FromStr` parses back.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Mode {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "classic" => Ok(Mode::Classic),
            "density" => Ok(Mode::Density),
            "adaptive" => Ok(Mode::Adaptive),
            _ => Err(Error::param(
                "mode",
                format!("`{s}` is not one of classic, density, adaptive"),
            )),
        }
    }
}

/// `N_MAX` of the paper's experiments, and the default budget.
pub const PAPER_N_MAX: u64 = 100_000;

/// The photon budget: the quality knob or `N_MAX` itself.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// Q in [0, 1]; `N_MAX = Q^2 * INT_MAX`.
    Quality(f64),
    /// `N_MAX` directly (the paper's experiments use 100 000). A target,
    /// not a cap on what is emitted: classic mode rounds each light's share
    /// of it and gives every light at least one photon (a few photons off
    /// `N_MAX` with several lights), adaptive mode gives each light up to
    /// `N_MAX` (more than `N_MAX` in all with several bright lights).
    /// `TraceReport::emitted` is the count.
    NMax(u64),
}

impl Default for Budget {
    /// [`PAPER_N_MAX`] photons.
    fn default() -> Self {
        Budget::NMax(PAPER_N_MAX)
    }
}

impl Budget {
    /// `N_MAX`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for Q outside [0, 1] or NaN.
    pub fn n_max(self) -> Result<u64> {
        match self {
            Budget::Quality(q) if (0.0..=1.0).contains(&q) => {
                Ok((q * q * INT_MAX as f64).round() as u64)
            }
            Budget::Quality(q) => Err(Error::param(
                "quality",
                format!("must be in [0, 1], got {q}"),
            )),
            Budget::NMax(n) => Ok(n),
        }
    }
}

/// Density control's target, in photons per unit area.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DensityTarget {
    /// `N_MAX / total surface area`: the density if every emitted photon's
    /// first hit were spread evenly over the scene.
    Auto,
    /// A given density (the experiments pass the classic mode's mean density
    /// with a diffuse light).
    PerArea(f64),
}

/// Everything a run needs besides the scene.
#[derive(Clone, Debug)]
pub struct TraceConfig {
    /// Which algorithm.
    pub mode: Mode,
    /// Q or `N_MAX`.
    pub budget: Budget,
    /// Seed of every random number.
    pub seed: u64,
    /// Bounces after the first hit; photons at this depth are stored but not continued.
    pub max_depth: u32,
    /// Per-hit cap on children (adaptive mode).
    pub split_cap: u32,
    /// Memory allowed for photons, in bytes; `None` means 7/8 of the available
    /// memory ([`default_memory_budget`]).
    pub memory_budget: Option<u64>,
    /// Which directionality estimator sets alpha_D (adaptive mode).
    pub estimator: Estimator,
    /// Constants of the directionality analysis.
    pub analysis: AnalysisParams,
    /// Target of density control.
    pub density_target: DensityTarget,
    /// Photons per parallel batch; results do not depend on it.
    pub batch: usize,
    /// Which emitted photons to trace (the whole run by default).
    pub shard: Shard,
    /// Importance from the camera in the counts (adaptive mode only, beyond
    /// the paper; docs/method.md, "Importance in the counts"): the pass to
    /// run first. `None`, the default, is the paper's counts.
    pub importance: Option<crate::importance::ImportanceConfig>,
}

impl Default for TraceConfig {
    /// The paper's adaptive mode with [`PAPER_N_MAX`] photons, every other
    /// setting at its default.
    fn default() -> Self {
        TraceConfig::new(Mode::Adaptive, Budget::default())
    }
}

impl TraceConfig {
    /// A run of `mode` with `N_MAX` photons and every other setting at its default.
    pub fn new(mode: Mode, budget: Budget) -> Self {
        TraceConfig {
            mode,
            budget,
            seed: 1,
            max_depth: DEFAULT_MAX_DEPTH,
            split_cap: DEFAULT_SPLIT_CAP,
            memory_budget: None,
            estimator: Estimator::Paper,
            analysis: AnalysisParams::default(),
            density_target: DensityTarget::Auto,
            batch: 1024,
            shard: Shard::WHOLE,
            importance: None,
        }
    }

    /// Checks every setting once and resolves the derived ones (`N_MAX`,
    /// the memory budget in bytes): the form the engine runs on.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the first bad setting.
    pub fn check(&self) -> Result<CheckedConfig> {
        let n_max = self.budget.n_max()?;
        if self.split_cap == 0 {
            return Err(Error::param("split cap", "must be at least 1"));
        }
        if self.max_depth > 250 {
            return Err(Error::param(
                "max depth",
                format!("must be at most 250, got {}", self.max_depth),
            ));
        }
        if let DensityTarget::PerArea(d) = self.density_target {
            if !(d.is_finite() && d > 0.0) {
                return Err(Error::param(
                    "density target",
                    format!("must be a positive number, got {d}"),
                ));
            }
        }
        self.shard.validate()?;
        if self.mode == Mode::Density && !self.shard.is_whole() {
            return Err(Error::param(
                "shard",
                "density control cannot be sharded: whether a photon is stored depends on \
                 every photon stored before it in the whole run (use classic or adaptive)",
            ));
        }
        if self.batch == 0 {
            return Err(Error::param("batch", "must be at least 1"));
        }
        if let Some(imp) = &self.importance {
            check_importance(self.mode, imp)?;
        }
        self.analysis.validate()?;
        Ok(CheckedConfig {
            raw: self.clone(),
            n_max,
            memory_budget: self
                .memory_budget
                .unwrap_or_else(|| default_memory_budget(available_memory())),
        })
    }

    /// Checks the settings ([`TraceConfig::check`] without keeping the result).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the first bad one.
    pub fn validate(&self) -> Result<()> {
        self.check().map(|_| ())
    }
}

/// Importance is an option of the adaptive counts, and its pass is the
/// whole pass in every photon shard (so that shards split the same way and
/// merge into the whole run).
fn check_importance(mode: Mode, imp: &crate::importance::ImportanceConfig) -> Result<()> {
    if mode != Mode::Adaptive {
        return Err(Error::param(
            "importance",
            format!("importance in the counts is an option of the adaptive mode, not {mode}"),
        ));
    }
    if !imp.shard.is_whole() {
        return Err(Error::param(
            "importance",
            "a trace runs the whole importance pass: its shard must be 0/1",
        ));
    }
    imp.validate()
}

/// A [`TraceConfig`] whose every invariant holds (the high-level form of the
/// settings, as ripgrep turns its low-level arguments into checked ones): the
/// only way to make one is [`TraceConfig::check`], and the engine takes
/// nothing else, so no setting is validated twice or forgotten.
#[derive(Clone, Debug)]
pub struct CheckedConfig {
    raw: TraceConfig,
    n_max: u64,
    memory_budget: u64,
}

impl CheckedConfig {
    /// The settings as given.
    pub fn settings(&self) -> &TraceConfig {
        &self.raw
    }
    /// The mode.
    pub fn mode(&self) -> Mode {
        self.raw.mode
    }
    /// `N_MAX` (from Q or given).
    pub fn n_max(&self) -> u64 {
        self.n_max
    }
    /// Seed of every random number.
    pub fn seed(&self) -> u64 {
        self.raw.seed
    }
    /// Bounce limit (at most 250).
    pub fn max_depth(&self) -> u32 {
        self.raw.max_depth
    }
    /// Per-hit cap on children (at least 1).
    pub fn split_cap(&self) -> u32 {
        self.raw.split_cap
    }
    /// Memory allowed for photons, in bytes (the default resolved).
    pub fn memory_budget(&self) -> u64 {
        self.memory_budget
    }
    /// The directionality estimator.
    pub fn estimator(&self) -> Estimator {
        self.raw.estimator
    }
    /// The analysis constants (validated).
    pub fn analysis(&self) -> &AnalysisParams {
        &self.raw.analysis
    }
    /// Density control's target (a positive density when given).
    pub fn density_target(&self) -> DensityTarget {
        self.raw.density_target
    }
    /// Photons per parallel batch (at least 1).
    pub fn batch(&self) -> usize {
        self.raw.batch
    }
}

/// The share of the available memory the budget takes when none is given,
/// as `(numerator, denominator)`: 7/8.
pub const DEFAULT_MEMORY_SHARE: (u64, u64) = (7, 8);

/// The memory budget when none is given: [`DEFAULT_MEMORY_SHARE`] of the
/// available memory. A stored photon costs 16 bytes and nothing else holds
/// photons (the kd-tree is built in place), so 1e9 photons (16 GB) fit on a
/// 24 GB machine.
pub fn default_memory_budget(available: u64) -> u64 {
    let (num, den) = DEFAULT_MEMORY_SHARE;
    available / den * num
}

/// Bytes of available memory (Linux `MemAvailable`), or 4 GiB when unknown.
pub fn available_memory() -> u64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("MemAvailable:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|kb| kb.parse::<u64>().ok())
        })
        .map(|kb| kb * 1024)
        .unwrap_or(4 << 30)
}
