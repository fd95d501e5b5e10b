//! # adaptive-pm
//!
//! Photon tracing through Intel Embree whose photon counts are set by the
//! scene itself, after Gautron, Blasi and Aveneau, *Paramétrage automatique
//! des algorithmes de rendu par méthodes de Monte-Carlo*: one quality knob Q
//! sets how many photons each light emits and how many a hit splits into,
//! from the energy, area and directionality of every emitter and BRDF.
//!
//! ```no_run
//! use adaptive_pm::embree::{thread_pool, Device};
//! use adaptive_pm::engine::{Budget, Maps, Mode, TraceConfig, Tracer};
//! use adaptive_pm::scene::Scene;
//!
//! let scene = Scene::cornell()?; // or Scene::load("scene.glb")?
//! let device = Device::new()?;
//! let rt = scene.commit(&device)?; // Embree geometry, Send + Sync
//! let pool = thread_pool(0)?; // rayon workers with FTZ/DAZ set for Embree
//! let mut tracer = Tracer::new(&scene, &rt);
//! let cfg = TraceConfig::new(Mode::Adaptive, Budget::NMax(100_000));
//! let run = pool.install(|| tracer.trace(&cfg))?;
//! let maps = Maps::build(&run.records); // kd-trees: all photons, first hits only
//! let mut nearest = Vec::new();
//! maps.full.nearest_k(glam::Vec3::new(278.0, 0.0, 279.5), 50, f32::INFINITY, &mut nearest);
//! # Ok::<(), adaptive_pm::Error>(())
//! ```
//!
//! Modules: [`scene`] (model, glTF, lights), [`brdf`] and [`emitter`] (one
//! file per model), [`analysis`] (directionality), [`engine`] (the wavefront
//! tracer in its three modes), [`photon_map`] (compact photon, kd-tree,
//! density), [`render`] (images from the map), [`experiments`] (the paper's
//! Cornell sweep), [`embree`] (the safe Embree layer). Errors: [`Error`].
#![warn(missing_docs)]
// `unsafe` lives in `embree-sys` and the one safe wrapper module below.
#![deny(unsafe_code)]

pub mod analysis;
pub mod brdf;
#[allow(unsafe_code)]
pub mod embree;
pub mod emitter;
pub mod engine;
pub mod error;
pub mod experiments;
pub mod photon_file;
pub mod photon_map;
pub mod render;
pub mod rng;
pub mod sampling;
pub mod scene;

pub use error::{Error, Result};
