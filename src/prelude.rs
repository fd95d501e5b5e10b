//! The types most programs need, in one import: `use adaptive_pm::prelude::*;`.
//!
//! Scene building ([`Scene`], [`Material`], [`Brdf`] and its models, [`CosN`]
//! emission), the photon map ([`PhotonMap`], [`PhotonRecord`], [`Neighbor`]),
//! the tracer and its configuration, the ray-casting trait, the renderer's
//! entry points, errors, and with the `embree` feature the Embree device and
//! the prepared-scene type a stored tracer holds (`EmbreeScene`:
//! `Tracer<CommittedScene>` traces one).

pub use crate::brdf::{Brdf, CookTorrance, GltfPbr, Lambert, Mirror, Phong};
pub use crate::emitter::CosN;
pub use crate::engine::{Budget, Mode, TraceConfig, TraceOutput, Tracer};
pub use crate::error::{Error, Result};
pub use crate::photon_map::{Neighbor, PhotonMap, PhotonRecord};
pub use crate::raycast::{Hit, Ray, RayCaster};
pub use crate::render::{
    irradiance_estimate, render, render_path, Image, Lookup, PathPart, RenderConfig, RenderMaps,
};
pub use crate::scene::{Camera, Emission, Light, Material, PreparedScene, Scene};

#[cfg(feature = "embree")]
#[cfg_attr(docsrs, doc(cfg(feature = "embree")))]
pub use crate::embree::{CommittedScene, Device, EmbreeScene};
