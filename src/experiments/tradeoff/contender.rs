//! What the trade study compares: the paper's three modes, and the adaptive
//! mode with importance in its counts (`--importance camera`), whose pass
//! matches the study's render (its camera, aspect and gather).

use crate::engine::{Budget, Mode, TraceConfig};
use crate::error::{Error, Result};
use crate::importance::ImportanceConfig;
use crate::render::RenderConfig;
use serde::Serialize;

/// One way of tracing the study measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Contender {
    /// [`Mode::Classic`].
    Classic,
    /// [`Mode::Density`].
    Density,
    /// [`Mode::Adaptive`], the paper's counts.
    Adaptive,
    /// [`Mode::Adaptive`] with `alpha_I` from an importance pass.
    Importance,
}

impl Contender {
    /// All of them, in the order the study reports them.
    pub const ALL: [Contender; 4] = [
        Contender::Classic,
        Contender::Density,
        Contender::Adaptive,
        Contender::Importance,
    ];

    /// The name on the command line and in the study's files.
    pub fn name(self) -> &'static str {
        match self {
            Contender::Importance => "importance",
            other => other.mode().name(),
        }
    }

    /// The engine's mode it traces with.
    pub fn mode(self) -> Mode {
        match self {
            Contender::Classic => Mode::Classic,
            Contender::Density => Mode::Density,
            Contender::Adaptive | Contender::Importance => Mode::Adaptive,
        }
    }

    /// The trace of a run at `n_max` and `seed` for renders like `rc`.
    pub fn trace_config(self, n_max: u64, seed: u64, rc: &RenderConfig) -> TraceConfig {
        let mut cfg = TraceConfig::new(self.mode(), Budget::NMax(n_max));
        cfg.seed = seed;
        if self == Contender::Importance {
            let mut imp = ImportanceConfig {
                seed,
                ..Default::default()
            };
            imp.match_render(rc);
            cfg.importance = Some(imp);
        }
        cfg
    }
}

impl From<Mode> for Contender {
    fn from(m: Mode) -> Self {
        match m {
            Mode::Classic => Contender::Classic,
            Mode::Density => Contender::Density,
            Mode::Adaptive => Contender::Adaptive,
        }
    }
}

impl std::fmt::Display for Contender {
    /// [`Contender::name`]: what `FromStr` parses back.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Contender {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Contender::ALL
            .into_iter()
            .find(|c| c.name() == s)
            .ok_or_else(|| {
                Error::param(
                    "mode",
                    format!("`{s}` is not one of classic, density, adaptive, importance"),
                )
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back_and_only_importance_traces_importance() {
        let rc = RenderConfig::new(64, 32);
        for c in Contender::ALL {
            assert_eq!(c.name().parse::<Contender>().unwrap(), c);
            let t = c.trace_config(1000, 5, &rc);
            assert_eq!(t.mode, c.mode());
            assert_eq!(t.importance.is_some(), c == Contender::Importance);
        }
        let imp = Contender::Importance
            .trace_config(1000, 5, &rc)
            .importance
            .unwrap();
        assert_eq!((imp.width, imp.height, imp.seed), (64, 32, 5));
        assert!("path".parse::<Contender>().is_err());
    }
}
