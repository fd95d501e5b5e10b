//! The growing hash-grid map against brute force, and power conservation when a
//! rejected photon's power is spread over its neighbours.
//!
//! The grid measures distances exactly as the brute force below does (f32
//! `length_squared` of the stored position), so distance lists must be equal bit for
//! bit; only which photons are kept among ties at the k-th distance may differ.

use adaptive_pm::photon_map::{GrowingMap, Neighbor, PhotonRecord};
use adaptive_pm::rng::Rng;
use glam::Vec3;

fn photon(position: Vec3) -> PhotonRecord {
    PhotonRecord {
        position,
        power: Vec3::new(0.5, 1.0, 2.0),
        direction: -Vec3::Z,
        depth: 1,
        caustic: false,
    }
}

fn brute(map: &GrowingMap, p: Vec3, k: usize, r: f32) -> Vec<Neighbor> {
    let mut all: Vec<Neighbor> = map
        .records()
        .iter()
        .enumerate()
        .map(|(i, rec)| Neighbor {
            index: i as u32,
            dist2: (rec.position - p).length_squared(),
        })
        .filter(|n| n.dist2 <= r * r)
        .collect();
    all.sort_by(|a, b| a.dist2.total_cmp(&b.dist2).then(a.index.cmp(&b.index)));
    all.truncate(k);
    all
}

fn check(map: &GrowingMap, p: Vec3, k: usize, r: f32, out: &mut Vec<Neighbor>) {
    map.nearest_k(p, k, r, out);
    let want = brute(map, p, k, r);
    let ctx = format!("p {p} k {k} r {r} n {}", map.len());
    let d = |v: &[Neighbor]| v.iter().map(|n| n.dist2).collect::<Vec<_>>();
    assert_eq!(d(out), d(&want), "{ctx}");
    let kth = want.last().map_or(0.0, |n| n.dist2);
    for (a, b) in out.iter().zip(&want) {
        if a.dist2 < kth {
            assert_eq!(a.index, b.index, "{ctx}");
        }
        let own = (map.photon(a.index).position - p).length_squared();
        assert_eq!(own, a.dist2, "{ctx}");
    }
}

fn queries(rng: &mut Rng, n: usize) -> Vec<Vec3> {
    (0..n)
        .map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 1.4 - 0.2)
        .collect()
}

#[test]
fn nearest_k_matches_brute_force_while_growing() {
    let mut rng = Rng::new(31);
    let mut out = Vec::new();
    // Cells from much smaller to larger than the neighbour distances; the tiny cells
    // force the switch from rings to a scan of the table.
    for cell in [0.002, 0.03, 0.1, 0.7, 5.0] {
        let mut map = GrowingMap::new(Vec3::ZERO, Vec3::ONE, cell).unwrap();
        for _ in 0..4 {
            for _ in 0..2500 {
                let p = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
                map.insert(photon(p));
            }
            for p in queries(&mut rng, 25) {
                for k in [1, 10, 50] {
                    for r in [f32::INFINITY, 0.05, 0.0] {
                        check(&map, p, k, r, &mut out);
                    }
                }
            }
        }
    }
}

#[test]
fn planar_lattice_and_outside_points_match_brute_force() {
    let mut rng = Rng::new(32);
    let mut map = GrowingMap::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), 0.05).unwrap();
    assert!(map.is_empty());
    for i in 0..2000 {
        // A lattice (ties) on z = 0, plus photons outside the bounds.
        let p = Vec3::new((i % 40) as f32 / 40.0, (i / 40) as f32 / 50.0, 0.0);
        map.insert(photon(p));
    }
    for _ in 0..200 {
        map.insert(photon(Vec3::new(rng.next_f32() * 3.0 - 1.0, -0.5, 0.3)));
    }
    let nan = map.insert(photon(Vec3::new(f32::NAN, 0.0, 0.0)));
    assert_eq!(nan, 2200);
    let mut out = Vec::new();
    for p in queries(&mut rng, 60) {
        for k in [1, 4, 30, 5000] {
            for r in [f32::INFINITY, 0.1] {
                check(&map, p * Vec3::new(1.0, 1.0, 0.1), k, r, &mut out);
            }
        }
    }
    map.nearest_k(Vec3::new(0.5, 0.5, 0.0), 10, f32::NAN, &mut out);
    assert!(out.is_empty());
    map.nearest_k(Vec3::new(f32::NAN, 0.5, 0.0), 10, 1.0, &mut out);
    assert!(out.is_empty());
}

#[test]
fn bad_parameters_are_errors() {
    assert!(GrowingMap::new(Vec3::ZERO, Vec3::ONE, 0.0).is_err());
    assert!(GrowingMap::new(Vec3::ZERO, Vec3::ONE, f32::NAN).is_err());
    assert!(GrowingMap::new(Vec3::ONE, Vec3::ZERO, 0.1).is_err());
    assert!(GrowingMap::new(Vec3::ZERO, Vec3::splat(f32::INFINITY), 0.1).is_err());
    assert!(GrowingMap::new(Vec3::ZERO, Vec3::splat(1e9), 1e-3).is_err());
    assert!(GrowingMap::new(Vec3::ZERO, Vec3::ZERO, 1.0).is_ok());
}

#[test]
fn spreading_a_rejected_photons_power_conserves_the_total() {
    let mut rng = Rng::new(33);
    let mut map = GrowingMap::new(Vec3::ZERO, Vec3::ONE, 0.05).unwrap();
    let mut expected = [0f64; 3];
    let add = |sum: &mut [f64; 3], p: Vec3| {
        for c in 0..3 {
            sum[c] += p[c] as f64;
        }
    };
    let mut out = Vec::new();
    for i in 0..3000 {
        let p = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        let power = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        add(&mut expected, power);
        // Every third photon after the first hundred is rejected.
        map.nearest_k(p, 8, f32::INFINITY, &mut out);
        if i > 100 && i % 3 == 0 {
            map.spread_power(&out, power);
        } else {
            map.insert(PhotonRecord {
                position: p,
                power,
                direction: Vec3::Z,
                depth: 0,
                caustic: false,
            });
        }
    }
    let mut total = [0f64; 3];
    let n = map.len();
    for r in map.into_records() {
        add(&mut total, r.power);
    }
    assert!(n < 3000);
    // Each f32 addition rounds by at most 2^-24 relative; a photon receives at most
    // a few hundred shares, so 1e-5 relative is a generous bound.
    for c in 0..3 {
        assert!(
            (total[c] - expected[c]).abs() <= 1e-5 * expected[c],
            "{total:?} vs {expected:?}"
        );
    }
}
