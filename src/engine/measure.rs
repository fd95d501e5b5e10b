//! The photon maps of a run and their quality (docs/method.md, "The photon map
//! and its measurements"): the full map and the map of primary photons
//! (stored at their first hit), each a balanced kd-tree, and the photon
//! density `k / (pi r_k^2)` over fixed surface points.

use crate::photon_map::{
    density_stats, density_stats_where, CompactPhoton, DensityStats, PhotonMap, PhotonRecord,
    Quantizer, DEFAULT_DENSITY_K,
};
use crate::scene::{Scene, SurfacePoint};
use glam::Vec3;
use rayon::prelude::*;
use std::time::Instant;

/// Evaluation points of the density statistics: enough that the max is
/// stable (the same points for every mode and run: docs/method.md, "Density
/// measurements").
pub const DENSITY_POINTS: usize = 4096;

/// Seed of the evaluation points (fixed, independent of the run's seed).
pub const DENSITY_POINTS_SEED: u64 = 0xDE45_1717;

/// The one map set of a run (the density measurements and the renderer read
/// it), with build times.
#[derive(Clone, Debug)]
pub struct Maps {
    /// All stored photons (the renderer's gather reads it at secondary hits).
    pub full: PhotonMap,
    /// Photons stored at their first hit only (the paper's primary map).
    pub primary: PhotonMap,
    /// Photons stored at depth >= 1 that are not caustic photons (the
    /// renderer's indirect light at a first hit, without a gather).
    pub indirect: PhotonMap,
    /// Caustic photons (`L S+ D`: through mirrors and glass only), read at
    /// a camera path's first non-specular hit with their own kernel.
    pub caustic: PhotonMap,
    /// Seconds to build `full`.
    pub build_s: f64,
    /// Seconds to build `primary`.
    pub build_primary_s: f64,
    /// Seconds to build `indirect`.
    pub build_indirect_s: f64,
    /// Seconds to build `caustic`.
    pub build_caustic_s: f64,
}

impl Maps {
    /// Builds the four kd-trees.
    pub fn build(records: &[PhotonRecord]) -> Self {
        let timed = |keep: fn(&PhotonRecord) -> bool| {
            let t = Instant::now();
            let map = PhotonMap::build_filtered(records, keep);
            (map, t.elapsed().as_secs_f64())
        };
        let (full, build_s) = timed(|_| true);
        let (primary, build_primary_s) = timed(|r| r.depth == 0);
        let (indirect, build_indirect_s) = timed(|r| r.depth >= 1 && !r.caustic);
        let (caustic, build_caustic_s) = timed(|r| r.caustic);
        Maps {
            full,
            primary,
            indirect,
            caustic,
            build_s,
            build_primary_s,
            build_indirect_s,
            build_caustic_s,
        }
    }

    /// Seconds to build all the maps.
    pub fn build_total_s(&self) -> f64 {
        self.build_s + self.build_primary_s + self.build_indirect_s + self.build_caustic_s
    }
}

/// The map of the photons of `photons` that `keep` selects (copied), and
/// the seconds it took.
fn subset(
    photons: &[CompactPhoton],
    frame: Quantizer,
    keep: fn(&CompactPhoton) -> bool,
) -> (PhotonMap, f64) {
    let t = Instant::now();
    let part: Vec<CompactPhoton> = photons
        .par_iter()
        .with_min_len(4096)
        .filter(|p| keep(p))
        .copied()
        .collect();
    (
        PhotonMap::from_compact(part, frame),
        t.elapsed().as_secs_f64(),
    )
}

impl Maps {
    /// The four kd-trees from a trace's compact photons, without decoding
    /// them: the full map is built in place over `photons`, the others over
    /// copies of their photons.
    pub fn from_photons(photons: Vec<CompactPhoton>, frame: Quantizer) -> Self {
        let (primary, build_primary_s) = subset(&photons, frame, |p| p.depth() == 0);
        let (indirect, build_indirect_s) =
            subset(&photons, frame, |p| p.depth() >= 1 && !p.is_caustic());
        let (caustic, build_caustic_s) = subset(&photons, frame, CompactPhoton::is_caustic);
        let t = Instant::now();
        let full = PhotonMap::from_compact(photons, frame);
        Maps {
            full,
            primary,
            indirect,
            caustic,
            build_s: t.elapsed().as_secs_f64(),
            build_primary_s,
            build_indirect_s,
            build_caustic_s,
        }
    }

    /// The full map and the caustic map, the full one built in place over
    /// `photons`; the primary and indirect maps are left empty. For a render
    /// that reads only those two (the default gather through the irradiance
    /// cache): at 1e6 photons it saves two of the builds.
    pub fn full_only(photons: Vec<CompactPhoton>, frame: Quantizer) -> Self {
        let (caustic, build_caustic_s) = subset(&photons, frame, CompactPhoton::is_caustic);
        let t = Instant::now();
        let full = PhotonMap::from_compact(photons, frame);
        Maps {
            full,
            primary: PhotonMap::from_compact(Vec::new(), frame),
            indirect: PhotonMap::from_compact(Vec::new(), frame),
            caustic,
            build_s: t.elapsed().as_secs_f64(),
            build_primary_s: 0.0,
            build_indirect_s: 0.0,
            build_caustic_s,
        }
    }

    /// These maps with their caustic map taken from a caustic pass
    /// ([`crate::engine::Tracer::trace_caustic`]) instead of the main
    /// trace's caustic photons, which stay in `full` (the gather reads them
    /// at secondary hits) but no longer in `caustic`: a caustic is counted
    /// once, from the pass. `build_caustic_s` adds the new tree's build
    /// to the time of the one it replaces (both were spent).
    pub fn with_caustic_pass(self, pass: super::CausticOutput) -> Self {
        let t = Instant::now();
        let caustic = pass.into_map();
        Maps {
            caustic,
            build_caustic_s: self.build_caustic_s + t.elapsed().as_secs_f64(),
            ..self
        }
    }

    /// True when the primary and indirect maps are empty but the full map
    /// is not: built by [`Maps::full_only`] (a real split of a non-empty
    /// map always has photons in one of them).
    pub fn is_full_only(&self) -> bool {
        !self.full.is_empty() && self.primary.is_empty() && self.indirect.is_empty()
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
pub fn map_metrics(maps: &Maps, points: &[SurfacePoint]) -> MapMetrics {
    MapMetrics {
        full: map_density(&maps.full, points),
        primary: map_density(&maps.primary, points),
        bytes_per_photon: maps.full.bytes_per_photon() as f64,
        checksum: maps.full.checksum(),
    }
}

/// The density evaluation points of `scene`: [`DENSITY_POINTS`] of them,
/// area-uniform, from [`DENSITY_POINTS_SEED`].
pub fn density_points(scene: &Scene) -> Vec<SurfacePoint> {
    scene
        .surface_sampler()
        .points(DENSITY_POINTS, DENSITY_POINTS_SEED)
}

/// The density statistics of `map` at `points`, over the
/// [`DEFAULT_DENSITY_K`] nearest photons. Photons of both sides count:
/// points are where the density is measured, whichever side of a surface
/// the light reached.
pub fn map_density(map: &PhotonMap, points: &[SurfacePoint]) -> DensityStats {
    let pts: Vec<(Vec3, Vec3)> = points.iter().map(|p| (p.position, Vec3::ZERO)).collect();
    density_stats(map, &pts, DEFAULT_DENSITY_K)
}

/// [`map_density`] of the primary photons (depth 0) of `full`, without
/// building their map: the values a primary map gives whose positions are
/// quantised as `full`'s are ([`Maps::from_photons`] builds it so), for the
/// peak memory of one map.
pub fn primary_density(full: &PhotonMap, points: &[SurfacePoint]) -> DensityStats {
    let pts: Vec<Vec3> = points.iter().map(|p| p.position).collect();
    density_stats_where(full, &pts, DEFAULT_DENSITY_K, |p| p.depth() == 0)
}
