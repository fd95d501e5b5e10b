//! Photon density statistics (docs/method.md, "Density measurements"): the
//! density at a surface point is `k / (pi r_k^2)` photons per unit area, with
//! `r_k` the distance to the k-th nearest photon; over a fixed set of
//! evaluation points (area-uniform on the scene's surfaces, the same for every
//! mode) the experiments report its maximum, mean, standard deviation and
//! standard deviation over mean.
//!
//! Choices:
//! - `k` defaults to [`DEFAULT_DENSITY_K`] = 50: the estimate's relative standard
//!   deviation is about `1 / sqrt(k - 2)` = 14% for a uniform density (r_k^2 of a
//!   Poisson process is Gamma-distributed), and its bias `k / (k - 1)` is 2%.
//! - Surface side: a point may come with a normal; only photons that arrived on the
//!   side it points to count (direction of travel `d` with `dot(d, n) <= 0`), so the
//!   two faces of a thin wall are not mixed. A zero normal counts every photon.
//! - Fewer than `k` photons (on that side) in the whole map: the estimate uses all
//!   of them, `found / (pi r_found^2)`; none gives 0.
//! - `r_k` is at least one quantisation step of the map (positions are not known
//!   more precisely), so coincident photons give a large but finite density.
//! - `sigma` is the population standard deviation over the points; `sigma_over_mean`
//!   is 0 when the mean is 0.

use super::{Neighbor, PhotonMap};
use glam::Vec3;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Default number of neighbours of the density estimate.
pub const DEFAULT_DENSITY_K: usize = 50;

/// Density (photons per unit area) at `p` from its `k` nearest photons of any side.
/// `scratch` is reused between calls to avoid allocating.
pub fn density_at(map: &PhotonMap, p: Vec3, k: usize, scratch: &mut Vec<Neighbor>) -> f32 {
    density_at_facing(map, p, Vec3::ZERO, k, scratch)
}

/// Density at `p` counting only photons that arrived on the side `normal` points to
/// (see the module docs; a zero `normal` counts all).
pub fn density_at_facing(
    map: &PhotonMap,
    p: Vec3,
    normal: Vec3,
    k: usize,
    scratch: &mut Vec<Neighbor>,
) -> f32 {
    let found = if normal == Vec3::ZERO {
        // No side test: the plain search skips decoding every direction.
        map.kth_nearest_where(p, k, scratch, |_| true)
    } else {
        map.kth_nearest_where(p, k, scratch, |c| {
            // As `PhotonMap::nearest_k_facing` tests the side.
            c.direction_unnormalised().dot(normal) <= 0.0
        })
    };
    density_of(map, found)
}

/// `found / (pi r^2)` from the count and squared distance of the farthest
/// of the neighbours found, `r` at least one quantisation step.
fn density_of(map: &PhotonMap, found: Option<(usize, f32)>) -> f32 {
    let Some((count, dist2)) = found else {
        return 0.0;
    };
    let step = map.quantizer().step();
    let r2 = (dist2 as f64).max(step * step);
    (count as f64 / (PI * r2)) as f32
}

/// Summary of the density over a set of evaluation points.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DensityStats {
    /// Largest density.
    pub max: f64,
    /// Mean density.
    pub mean: f64,
    /// Population standard deviation of the density.
    pub sigma: f64,
    /// `sigma / mean` (0 when the mean is 0).
    pub sigma_over_mean: f64,
    /// Number of evaluation points.
    pub points: usize,
    /// Index of the first point holding the largest density (0 without points):
    /// where the peak is, for a report to name its mesh and position.
    pub argmax: usize,
}

/// Density statistics over `points` (position, normal; see the module docs) with `k`
/// neighbours. Parallel over the points; the reduction is sequential in point order,
/// so the result does not depend on the thread count. No point gives all zeros.
pub fn density_stats(map: &PhotonMap, points: &[(Vec3, Vec3)], k: usize) -> DensityStats {
    let densities: Vec<f64> = points
        .par_iter()
        .map_init(Vec::new, |scratch, &(p, n)| {
            density_at_facing(map, p, n, k, scratch) as f64
        })
        .collect();
    summarize(&densities)
}

/// [`density_stats`] counting only the photons `accept` keeps (any side):
/// for instance the primary photons of a full map, `|p| p.depth() == 0`,
/// which gives the primary map's statistics without building it.
pub fn density_stats_where<F>(map: &PhotonMap, points: &[Vec3], k: usize, accept: F) -> DensityStats
where
    F: Fn(&crate::photon_map::CompactPhoton) -> bool + Sync,
{
    let densities: Vec<f64> = points
        .par_iter()
        .map_init(Vec::new, |scratch, &p| {
            // As `density_at` computes it, so the values match a map built
            // from the accepted photons alone.
            density_of(map, map.kth_nearest_where(p, k, scratch, &accept)) as f64
        })
        .collect();
    summarize(&densities)
}

/// Max and where it is, mean and population standard deviation (two passes,
/// in order).
fn summarize(values: &[f64]) -> DensityStats {
    if values.is_empty() {
        return DensityStats::default();
    }
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
    let sigma = var.sqrt();
    let argmax = (0..values.len()).fold(0, |b, i| if values[i] > values[b] { i } else { b });
    DensityStats {
        max: values.iter().copied().fold(0.0, f64::max),
        mean,
        sigma,
        sigma_over_mean: if mean > 0.0 { sigma / mean } else { 0.0 },
        points: values.len(),
        argmax,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summary_of_known_values() {
        let s = summarize(&[1.0, 3.0]);
        assert_eq!((s.max, s.mean, s.sigma, s.points), (3.0, 2.0, 1.0, 2));
        assert_eq!(s.argmax, 1);
        assert_eq!(
            summarize(&[2.0, 5.0, 5.0, 1.0]).argmax,
            1,
            "the first of a tie"
        );
        assert_eq!(s.sigma_over_mean, 0.5);
        assert_eq!(summarize(&[]), DensityStats::default());
        assert_eq!(summarize(&[0.0, 0.0]).sigma_over_mean, 0.0);
    }
}
