//! # adaptive-pm
//!
//! Photon tracing through Intel Embree whose photon counts are set by the
//! scene itself, after Gautron, Blasi and Aveneau, *Paramétrage automatique
//! des algorithmes de rendu par méthodes de Monte-Carlo*: one quality knob Q
//! sets how many photons each light emits and how many a hit splits into,
//! from the energy, area and directionality of every emitter and BRDF.
#![warn(missing_docs)]

pub mod analysis;
pub mod brdf;
pub mod embree;
pub mod emitter;
pub mod engine;
pub mod error;
pub mod experiments;
pub mod photon_map;
pub mod render;
pub mod rng;
pub mod sampling;
pub mod scene;

pub use error::{Error, Result};
