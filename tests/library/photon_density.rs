//! The density estimate `k / (pi r_k^2)` on a uniform planar distribution whose
//! density is known.
//!
//! Oracle: N uniform points in the unit square have density N per unit area. For a
//! Poisson process of density D, `pi r_k^2 D` is Gamma(k, 1), so the estimate has
//! mean `D k / (k - 1)` and relative standard deviation `1 / sqrt(k - 2)`. The
//! evaluation points are a lattice in [0.2, 0.8]^2 spaced farther apart than two
//! `r_k`, so their estimates are nearly independent (and their discs never leave the
//! square).

use adaptive_pm::photon_map::{
    density_at, density_at_facing, density_stats, PhotonMap, PhotonRecord, DEFAULT_DENSITY_K,
};
use adaptive_pm::rng::Rng;
use glam::Vec3;

const N: usize = 20_000;

/// N uniform photons on z = 0; `from_above(i)` says whether photon i travels down.
fn planar_map(from_above: impl Fn(usize) -> bool) -> PhotonMap {
    let mut rng = Rng::new(41);
    let records: Vec<PhotonRecord> = (0..N)
        .map(|i| PhotonRecord {
            position: Vec3::new(rng.next_f32(), rng.next_f32(), 0.0),
            power: Vec3::ONE,
            direction: if from_above(i) { -Vec3::Z } else { Vec3::Z },
            depth: 0,
        })
        .collect();
    PhotonMap::build(&records)
}

/// An m x m lattice in [0.2, 0.8]^2 with normal +z.
fn lattice(m: usize) -> Vec<(Vec3, Vec3)> {
    (0..m * m)
        .map(|i| {
            let (x, y) = ((i % m) as f32 + 0.5, (i / m) as f32 + 0.5);
            let p = Vec3::new(0.2 + 0.6 * x / m as f32, 0.2 + 0.6 * y / m as f32, 0.0);
            (p, Vec3::Z)
        })
        .collect()
}

#[test]
fn uniform_planar_density_is_recovered() {
    let k = DEFAULT_DENSITY_K;
    let m = 10;
    // r_k = sqrt(k / (pi N)) = 0.028 < spacing / 2 = 0.03.
    let map = planar_map(|_| true);
    let stats = density_stats(&map, &lattice(m), k);
    assert_eq!(stats.points, m * m);
    let rel_sd = 1.0 / ((k - 2) as f64).sqrt();
    let expected = N as f64 * k as f64 / (k - 1) as f64;
    // 4 standard errors of a mean of m^2 independent estimates.
    let tol = 4.0 * expected * rel_sd / m as f64;
    assert!(
        (stats.mean - expected).abs() <= tol,
        "mean {} expected {expected} +- {tol}",
        stats.mean
    );
    // A sample standard deviation over m^2 values has relative standard error about
    // sqrt((kurtosis - 1) / (4 m^2)); the inverse Gamma(50) has kurtosis ~ 3.7, so
    // 0.08; four of them is 0.33.
    assert!(
        (stats.sigma_over_mean / rel_sd - 1.0).abs() <= 0.33,
        "sigma/mean {} expected {rel_sd}",
        stats.sigma_over_mean
    );
    assert!(stats.max >= stats.mean && stats.max <= stats.mean * (1.0 + 6.0 * rel_sd));
    // Deterministic whatever the thread count.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    assert_eq!(pool.install(|| density_stats(&map, &lattice(m), k)), stats);
}

#[test]
fn only_photons_arriving_on_the_normal_side_count() {
    let k = DEFAULT_DENSITY_K;
    let m = 10;
    // Half the photons arrive from below: the density seen from above halves.
    let map = planar_map(|i| i % 2 == 0);
    let up = density_stats(&map, &lattice(m), k);
    let expected = (N / 2) as f64 * k as f64 / (k - 1) as f64;
    let rel_sd = 1.0 / ((k - 2) as f64).sqrt();
    let tol = 4.0 * expected * rel_sd / m as f64;
    assert!(
        (up.mean - expected).abs() <= tol,
        "{} vs {expected}",
        up.mean
    );
    let down: Vec<_> = lattice(m).into_iter().map(|(p, _)| (p, -Vec3::Z)).collect();
    let down = density_stats(&map, &down, k);
    assert!(
        (down.mean - expected).abs() <= tol,
        "{} vs {expected}",
        down.mean
    );
    // No normal: every photon counts.
    let mut scratch = Vec::new();
    let p = Vec3::new(0.5, 0.5, 0.0);
    let all = density_at(&map, p, k, &mut scratch);
    let side = density_at_facing(&map, p, Vec3::Z, k, &mut scratch);
    assert!(all > side);
}

#[test]
fn small_and_empty_maps() {
    let mut scratch = Vec::new();
    let empty = PhotonMap::build(&[]);
    assert_eq!(density_at(&empty, Vec3::ZERO, 10, &mut scratch), 0.0);
    let stats = density_stats(&empty, &[(Vec3::ZERO, Vec3::Z)], 10);
    assert_eq!(
        (stats.mean, stats.sigma_over_mean, stats.points),
        (0.0, 0.0, 1)
    );
    assert_eq!(density_stats(&empty, &[], 10).points, 0);
    // Three photons at distance 1: fewer than k, so all three over the disc of radius 1.
    let records: Vec<_> = [Vec3::X, Vec3::Y, -Vec3::X]
        .map(|p| PhotonRecord {
            position: p,
            power: Vec3::ONE,
            direction: -Vec3::Z,
            depth: 0,
        })
        .to_vec();
    let map = PhotonMap::build(&records);
    let d = density_at(&map, Vec3::ZERO, 10, &mut scratch);
    assert!((d - 3.0 / std::f32::consts::PI).abs() < 1e-5, "{d}");
    // Coincident photons: finite (r_k is at least one quantisation step).
    let same = PhotonMap::build(&[records[0]; 60]);
    assert!(density_at(&same, Vec3::X, 50, &mut scratch).is_finite());
}
