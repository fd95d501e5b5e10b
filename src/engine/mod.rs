//! The photon engine: wavefront tracing in three modes (docs/method.md,
//! "Photon counts", "Caps and global budget" and "The three modes"), and a
//! caustic pass aimed at the specular objects ([`caustic`], docs/method.md,
//! "The caustic pass").
//!
//! ```no_run
//! use adaptive_pm::embree::Device;
//! use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
//! use adaptive_pm::scene::Scene;
//!
//! let scene = Scene::cornell()?;
//! let device = Device::new()?;
//! // The scene and its Embree geometry, owned together: a 'static tracer.
//! let tracer = Tracer::new(scene.commit(&device)?);
//! let run = tracer.trace(&TraceConfig::new(Mode::Adaptive, Budget::NMax(100_000)))?;
//! println!("{} photons stored", run.report.stored);
//! # Ok::<(), adaptive_pm::Error>(())
//! ```

pub mod albedo;
pub(crate) mod buffer;
pub mod caustic;
pub mod caustic_aim;
pub mod caustic_budget;
pub mod caustic_emit;
pub mod config;
pub mod counts;
mod density_control;
pub mod measure;
mod queue;
pub mod report;
pub mod shard;
pub mod stream;
pub mod tracer;
pub mod wave;

pub use buffer::{map_frame, POWER_HEADROOM};
pub use caustic::{default_caustic_photons, CausticBudget, CausticOutput, CausticReport};
pub use caustic_aim::CausticAim;
pub use config::{Budget, CheckedConfig, DensityTarget, Mode, TraceConfig, PAPER_N_MAX};
pub use measure::{density_points, map_density, map_metrics, primary_density, MapMetrics, Maps};
pub use report::{DepthStats, ImportanceReport, TraceReport};
pub use shard::Shard;
pub use tracer::{TraceOutput, TraceProgress, Tracer};
