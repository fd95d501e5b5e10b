//! The photon map (docs/method.md, "The photon map and its measurements"):
//! photons stored at non-specular hits, kept compact (16 bytes each,
//! [`photon`]) in a balanced kd-tree in one flat array
//! ([`PhotonMap`], built in [`kdtree`], queried in [`query`]) and the
//! photon-density statistics the experiments report ([`density`]).
//!
//! Indices: a [`Neighbor::index`] of a [`PhotonMap`] is a position in the map's own
//! (tree) order, to be read back with [`PhotonMap::photon`]; it is not the index of the
//! record the map was built from.
//!
//! Primary photons only: build a second map with
//! `PhotonMap::build_filtered(&records, |r| r.depth == 0)`; caustic photons
//! only, with `|r| r.caustic`.

use glam::Vec3;

mod boxes;
pub mod density;
pub mod kdtree;
mod owners;
pub mod photon;
pub mod query;
mod stems;

pub use density::{
    density_at, density_at_facing, density_stats, density_stats_where, DensityStats,
    DEFAULT_DENSITY_K,
};
pub use kdtree::PhotonMap;
pub use photon::{CompactPhoton, Quantizer};

/// A photon as the tracer produces it (uncompressed; 40 bytes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhotonRecord {
    /// Where it hit (world units).
    pub position: Vec3,
    /// Its power (RGB, watts or the scene's unit); non-negative.
    pub power: Vec3,
    /// Its direction of travel when it hit (unit vector, pointing into the surface).
    pub direction: Vec3,
    /// Bounce depth: 0 when stored at its first hit after leaving the light.
    pub depth: u8,
    /// A caustic photon (`L S+ D`): every bounce since the light was on a
    /// specular surface (a mirror or glass), and there was at least one.
    pub caustic: bool,
}

/// One query result.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbor {
    /// The photon's index in the map that answered (see the module docs).
    pub index: u32,
    /// Squared distance to the query point (world units squared).
    pub dist2: f32,
}
