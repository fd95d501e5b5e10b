//! # adaptive-pm
//!
//! Photon tracing through Intel Embree whose photon counts are set by the
//! scene itself, after Gautron, Blasi and Aveneau, *Paramétrage automatique
//! des algorithmes de rendu par méthodes de Monte-Carlo*: one quality knob Q
//! sets how many photons each light emits and how many a hit splits into,
//! from the energy, area and directionality of every emitter and BRDF.
//!
//! # A scene built in code, traced and queried
//!
//! A grey floor under a square light that faces down, committed to Embree,
//! traced, and its photon map queried. Needs the feature `embree` (the
//! scene alone needs none):
//!
//! ```
//! # #[cfg(feature = "embree")] {
//! use adaptive_pm::embree::thread_pool;
//! use adaptive_pm::prelude::*;
//! use adaptive_pm::glam::Vec3; // the glam this crate uses, re-exported
//!
//! let mut scene = Scene::new();
//! let grey = scene.add_material(Material {
//!     name: "grey".into(),
//!     brdf: Brdf::Lambert(Lambert { albedo: Vec3::splat(0.5) }),
//!     emission: None,
//! });
//! let lamp = scene.add_material(Material {
//!     name: "lamp".into(),
//!     brdf: Brdf::Lambert(Lambert { albedo: Vec3::ZERO }),
//!     // Radiance 10 W/(m^2 sr), diffuse (cos^0) profile.
//!     emission: Some(Emission::new(Vec3::splat(10.0), CosN::new(0.0)?)),
//! });
//! let quad = |y: f32, s: f32| vec![
//!     Vec3::new(-s, y, -s), Vec3::new(s, y, -s), Vec3::new(s, y, s), Vec3::new(-s, y, s),
//! ];
//! // Triangles wind counter-clockwise around the side they face: up for the floor,
//! scene.add_mesh("floor", quad(0.0, 1.0), vec![[0, 2, 1], [0, 3, 2]], grey)?;
//! // down for the lamp (an emissive mesh becomes an area light).
//! scene.add_mesh("lamp", quad(1.0, 0.25), vec![[0, 1, 2], [0, 2, 3]], lamp)?;
//! assert_eq!((scene.triangle_count(), scene.lights().len()), (4, 1));
//!
//! // The scene and its Embree geometry, owned together and checked once:
//! // 'static, Send + Sync, so a renderer can store the tracer and share it.
//! let tracer: Tracer<CommittedScene> = Tracer::new(scene.commit(&Device::new()?)?);
//! let pool = thread_pool(2)?; // rayon workers with FTZ/DAZ set for Embree
//! let run = pool.install(|| tracer.trace(&TraceConfig::new(Mode::Adaptive, Budget::NMax(5_000))))?;
//! assert_eq!(run.report.emitted, 5_000);
//!
//! let map: PhotonMap = run.into_map(); // balanced kd-tree over every stored photon
//! let below_lamp = Vec3::new(0.0, 0.0, 0.0);
//! let mut nearest = Vec::new();
//! map.nearest_k(below_lamp, 50, f32::INFINITY, &mut nearest);
//! assert_eq!(nearest.len(), 50);
//! assert!(nearest.windows(2).all(|w| w[0].dist2 <= w[1].dist2)); // closest first
//!
//! // Irradiance under the lamp: a small square source of power P = L A pi at
//! // height h gives about P / (pi h^2) = L A / h^2 = 2.5 W/m^2.
//! let lookup = Lookup { k: 200, max_radius: 0.5 };
//! let e = irradiance_estimate(&map, below_lamp, Vec3::Y, lookup, &mut nearest);
//! let e = e.value.x;
//! assert!((1.8..2.6).contains(&e), "{e}");
//! # }
//! # Ok::<(), adaptive_pm::Error>(())
//! ```
//!
//! An image of it: [`render::render`] over the same prepared scene
//! (`render(tracer.prepared(), Some(&maps), &cfg)`), whose module page has
//! the example; it reads rays through any [`raycast::RayCaster`], so it
//! needs no feature with a caster of your own.
//!
//! # A photon map from your own photons
//!
//! [`photon_map::PhotonMap::build`] takes any photon records, for instance
//! from a tracer of your own:
//!
//! ```
//! use adaptive_pm::photon_map::{PhotonMap, PhotonRecord};
//! use glam::Vec3;
//!
//! let records: Vec<PhotonRecord> = (0..1000)
//!     .map(|i| PhotonRecord {
//!         position: Vec3::new((i % 10) as f32, 0.0, (i / 10) as f32 * 0.1),
//!         power: Vec3::splat(0.001),
//!         direction: Vec3::NEG_Y,
//!         depth: 0,
//!         caustic: false,
//!     })
//!     .collect();
//! let map = PhotonMap::build(&records);
//! let mut near = Vec::new();
//! map.nearest_k(Vec3::new(3.0, 0.0, 5.0), 4, f32::INFINITY, &mut near);
//! // Indices are the map's own (tree) order: read the photon back from the map.
//! let closest = map.photon(near[0].index);
//! assert!((closest.position - Vec3::new(3.0, 0.0, 5.0)).length() < 1e-3);
//! ```
//!
//! Modules: [`scene`] (model, glTF, lights), [`brdf`] and [`emitter`] (one
//! file per model), [`analysis`] (directionality), [`engine`] (the wavefront
//! tracer in its three modes), [`raycast`] (the ray-casting trait the tracer
//! and the renderer are generic over), [`photon_map`] (compact photon,
//! kd-tree, density), [`render`] (images from the map, and the path tracer),
//! and `embree` (the safe Embree layer) with the `embree` feature. Common
//! imports: [`prelude`]. Errors: [`Error`]. The crate re-exports the [`glam`]
//! and [`rayon`] it is built with, so your vectors and thread pools are its
//! own types whatever versions your crate depends on.
//!
//! # Features
//!
//! | feature | default | what it brings |
//! |---|---|---|
//! | `embree` | yes | `embree` (the Intel Embree ray caster, through `adaptive-pm-embree-sys`), `Scene::commit`, photon files |
//! | `gltf` | yes | `Scene::load` of glTF 2.0 files (PNG and JPEG textures included) and the built-in Cornell box |
//! | `image-io` | yes | OpenEXR and PNG image files (`render::Image::write_exr`, `write_png`) |
//! | `experiments` | with `cli` | the paper's experiments and their plots (`experiments`, for the command line: not a stable API) |
//! | `cli` | yes | the `adaptive-pm` binary |
//!
//! [`photon_map`], [`brdf`], [`emitter`], [`analysis`], [`scene`] (built in
//! code), [`engine`] and [`render`] (over a [`raycast::RayCaster`] of your
//! own), [`sampling`] and [`rng`] build with no feature at all: no Embree,
//! no libclang (16 crates). A renderer that traces with Embree and brings its
//! own scenes and image files depends on
//! `adaptive-pm = { version = "0.1", default-features = false, features = ["embree"] }`
//! (40 crates); one that also loads glTF and writes OpenEXR adds
//! `"gltf", "image-io"` (78 crates; `scripts/count-deps.sh` prints them).
#![warn(missing_docs, missing_debug_implementations)]
#![cfg_attr(docsrs, feature(doc_cfg))]
// `unsafe` lives in `embree-sys` and the one safe wrapper module below.
#![deny(unsafe_code)]

pub mod analysis;
pub mod brdf;
#[cfg(feature = "embree")]
#[cfg_attr(docsrs, doc(cfg(feature = "embree")))]
#[allow(unsafe_code)]
pub mod embree;
pub mod emitter;
pub mod engine;
pub mod error;
pub mod importance;
pub mod input;
pub mod isa;
// The paper's experiments drive the command line; they are not a stable API.
#[cfg(feature = "experiments")]
#[doc(hidden)]
pub mod experiments;
pub mod output;
#[cfg(feature = "embree")]
#[cfg_attr(docsrs, doc(cfg(feature = "embree")))]
pub mod photon_file;
pub mod photon_map;
pub mod prelude;
pub mod raycast;
pub mod render;
pub mod rng;
pub mod sampling;
pub mod scene;

pub use error::{Error, Result};
// The versions this crate is built with: a user's `Vec3` and thread pool
// are these, whatever glam or rayon their own crate names.
pub use glam;
pub use rayon;
