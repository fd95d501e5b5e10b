//! The photon maps of a run and their quality (SPEC §3): the full map and the
//! map of primary photons (stored at their first hit), each a balanced kd-tree,
//! and the photon density `k / (pi r_k^2)` over fixed surface points.

use crate::photon_map::{
    density_stats, CompactPhoton, DensityStats, PhotonMap, PhotonRecord, Quantizer,
};
use crate::scene::SurfacePoint;
use rayon::prelude::*;
use std::time::Instant;

/// k of the density estimate `k / (pi r_k^2)`.
pub const DENSITY_K: usize = 50;

/// Evaluation points of the density statistics: enough that the max is
/// stable (SPEC: the same points for every mode and run).
pub const DENSITY_POINTS: usize = 4096;

/// Seed of the evaluation points (fixed, independent of the run's seed).
pub const DENSITY_POINTS_SEED: u64 = 0xDE45_1717;

/// Both maps of a run, with their build times.
#[derive(Debug)]
pub struct Maps {
    /// All stored photons.
    pub full: PhotonMap,
    /// Photons stored at their first hit only.
    pub primary: PhotonMap,
    /// Seconds to build `full`.
    pub build_s: f64,
    /// Seconds to build `primary`.
    pub build_primary_s: f64,
}

impl Maps {
    /// Builds both kd-trees.
    pub fn build(records: &[PhotonRecord]) -> Self {
        let t = Instant::now();
        let full = PhotonMap::build(records);
        let build_s = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let primary_records: Vec<PhotonRecord> =
            records.iter().filter(|r| r.depth == 0).copied().collect();
        let primary = PhotonMap::build(&primary_records);
        let build_primary_s = t.elapsed().as_secs_f64();
        Maps {
            full,
            primary,
            build_s,
            build_primary_s,
        }
    }
}

impl Maps {
    /// Both kd-trees from a trace's compact photons, without decoding them:
    /// the full map is built in place over `photons`, the primary map over a
    /// copy of the depth-0 photons.
    pub fn from_photons(photons: Vec<CompactPhoton>, frame: Quantizer) -> Self {
        let t = Instant::now();
        let primary: Vec<CompactPhoton> = photons
            .par_iter()
            .with_min_len(4096)
            .filter(|p| p.depth() == 0)
            .copied()
            .collect();
        let primary = PhotonMap::from_compact(primary, frame);
        let build_primary_s = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let full = PhotonMap::from_compact(photons, frame);
        Maps {
            full,
            primary,
            build_s: t.elapsed().as_secs_f64(),
            build_primary_s,
        }
    }
}

/// Density statistics of both maps.
#[derive(Clone, Debug)]
pub struct MapMetrics {
    /// Full map.
    pub full: DensityStats,
    /// Primary photons only.
    pub primary: DensityStats,
    /// Bytes per stored photon in the kd-tree.
    pub bytes_per_photon: f64,
    /// Hash of the full map's contents.
    pub checksum: u64,
}

/// Evaluates the density of both maps at `points`.
pub fn measure(maps: &Maps, points: &[SurfacePoint]) -> MapMetrics {
    // A zero normal counts photons from both sides: points are where the
    // density is measured, whichever side of a surface the light reached.
    let pts: Vec<(glam::Vec3, glam::Vec3)> = points
        .iter()
        .map(|p| (p.position, glam::Vec3::ZERO))
        .collect();
    MapMetrics {
        full: density_stats(&maps.full, &pts, DENSITY_K),
        primary: density_stats(&maps.primary, &pts, DENSITY_K),
        bytes_per_photon: maps.full.bytes_per_photon() as f64,
        checksum: maps.full.checksum(),
    }
}
