//! The paper's experiments reproduced (docs/method.md, "The experiments"):
//! the Cornell sweep ([`cornell::run_cornell`]), its output files and figures
//! ([`output::write_outputs`]) and the paper's claims checked against it
//! ([`claims::check_claims`]); the renderer against the path tracer at
//! equal error ([`render_study`], `bench render`); the trade study
//! ([`tradeoff`]).
//!
//! ```no_run
//! use adaptive_pm::experiments::{cornell, output, sweep};
//!
//! let mut cfg = cornell::CornellConfig::paper();
//! cfg.n_values = sweep::parse_sweep("0,20,200")?;
//! cfg.n_max = 5_000;
//! let results = cornell::run_cornell(&cfg, &|_| {})?;
//! output::write_outputs(&results, std::path::Path::new("bench-out/demo"))?;
//! print!("{}", output::claims_table(&results));
//! # Ok::<(), adaptive_pm::Error>(())
//! ```

pub mod claims;
pub mod cornell;
pub mod output;
pub mod plot;
pub mod render_study;
pub mod sweep;
pub mod tradeoff;
