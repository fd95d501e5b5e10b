//! The photon map's kd-tree against brute force, its determinism, and the compact
//! photon's precision bounds.
//!
//! Tolerances: the tree measures distances on quantised coordinates in grid units,
//! brute force on decoded f32 world positions; the two differ by f32 rounding of
//! coordinates (relative 2^-24 of the largest coordinate magnitude, a few times), so
//! distances are compared within `1e-6 * magnitude` (about 8 ulps).

use adaptive_pm::photon_map::photon::{MAX_DEPTH, MAX_DIRECTION_ERROR, POWER_RELATIVE_ERROR};
use adaptive_pm::photon_map::{Neighbor, PhotonMap, PhotonRecord, Quantizer};
use adaptive_pm::rng::Rng;
use glam::Vec3;

fn record(position: Vec3, rng: &mut Rng) -> PhotonRecord {
    PhotonRecord {
        position,
        power: Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()),
        direction: random_direction(rng),
        depth: (rng.next_u32() % 8) as u8,
        caustic: false,
    }
}

fn random_direction(rng: &mut Rng) -> Vec3 {
    let z = 2.0 * rng.next_f32() - 1.0;
    let phi = std::f32::consts::TAU * rng.next_f32();
    adaptive_pm::sampling::spherical_direction(z, phi)
}

fn random_records(n: usize, seed: u64) -> Vec<PhotonRecord> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| {
            let p = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            record(p, &mut rng)
        })
        .collect()
}

/// Every photon's decoded distance to `p`, as (dist2, index), sorted.
fn brute(map: &PhotonMap, p: Vec3) -> Vec<(f32, u32)> {
    let mut all: Vec<(f32, u32)> = map
        .iter()
        .enumerate()
        .map(|(i, r)| ((r.position - p).length_squared(), i as u32))
        .collect();
    all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    all
}

/// Distance tolerance (world units) for a query at `p`.
fn tolerance(map: &PhotonMap, p: Vec3) -> f32 {
    let magnitude = map
        .iter()
        .map(|r| r.position.abs().max_element())
        .fold(p.abs().max_element(), f32::max);
    1e-6 * (magnitude + 1e-30) + map.quantizer().step() as f32 * 1e-6
}

fn check_knn(map: &PhotonMap, p: Vec3, k: usize, r: f32, out: &[Neighbor]) {
    let tol = tolerance(map, p);
    let all = brute(map, p);
    let dist = |d2: f32| d2.sqrt();
    let strict = all.iter().filter(|e| dist(e.0) < r - tol).count();
    let loose = all.iter().filter(|e| dist(e.0) <= r + tol).count();
    let ctx = format!("p {p} k {k} r {r} n {}", map.len());
    assert!(
        out.len() >= k.min(strict) && out.len() <= k.min(loose),
        "{ctx}: {} results, brute force {strict}..{loose}",
        out.len()
    );
    let mut seen = std::collections::HashSet::new();
    for (j, n) in out.iter().enumerate() {
        assert!(seen.insert(n.index), "{ctx}: duplicate {}", n.index);
        if j > 0 {
            assert!(out[j - 1].dist2 <= n.dist2, "{ctx}: not sorted");
        }
        // The j-th distance is the true j-th distance ...
        assert!(
            (dist(n.dist2) - dist(all[j].0)).abs() <= tol,
            "{ctx}: rank {j}: {} vs brute {}",
            n.dist2,
            all[j].0
        );
        // ... and the photon reported is at that distance.
        let own = (map.photon(n.index).position - p).length_squared();
        assert!(
            (dist(n.dist2) - dist(own)).abs() <= tol,
            "{ctx}: index/distance mismatch"
        );
    }
}

fn check_within(map: &PhotonMap, p: Vec3, r: f32, out: &[Neighbor]) {
    let tol = tolerance(map, p);
    let all = brute(map, p);
    let ctx = format!("p {p} r {r} n {}", map.len());
    let found: std::collections::HashSet<u32> = out.iter().map(|n| n.index).collect();
    assert_eq!(found.len(), out.len(), "{ctx}: duplicates");
    for (d2, i) in &all {
        if d2.sqrt() < r - tol {
            assert!(found.contains(i), "{ctx}: missed {i} at {}", d2.sqrt());
        }
    }
    for n in out {
        let own = (map.photon(n.index).position - p).length_squared();
        assert!(own.sqrt() <= r + tol, "{ctx}: {} is outside", n.index);
        assert!(
            (own.sqrt() - n.dist2.sqrt()).abs() <= tol,
            "{ctx}: distance"
        );
    }
}

/// Queries inside, on and around the map; several k and radii.
fn check_queries(map: &PhotonMap, seed: u64, queries: usize) {
    let mut rng = Rng::new(seed);
    let mut out = Vec::new();
    let n = map.len();
    let mut points: Vec<Vec3> = (0..queries)
        .map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 3.0 - 1.5)
        .collect();
    // Queries exactly at photons (radius 0 must find them).
    points.extend((0..n.min(5)).map(|i| map.photon(i as u32).position));
    for &p in &points {
        for &k in &[1, 7, 50, n + 3] {
            for &r in &[f32::INFINITY, 0.3, 0.0] {
                map.nearest_k(p, k, r, &mut out);
                check_knn(map, p, k, r, &out);
            }
        }
        for &r in &[0.0, 0.1, 0.4, f32::INFINITY] {
            map.within_radius(p, r, &mut out);
            check_within(map, p, r, &out);
        }
    }
}

#[test]
fn random_inputs_match_brute_force() {
    for (n, queries) in [(0, 10), (1, 10), (2, 10), (1000, 60), (20_000, 12)] {
        let map = PhotonMap::build(&random_records(n, 11 + n as u64));
        assert_eq!(map.len(), n);
        check_queries(&map, 5, queries);
    }
}

#[test]
fn degenerate_inputs_match_brute_force() {
    let mut rng = Rng::new(3);
    let same: Vec<_> = (0..300)
        .map(|_| record(Vec3::new(0.25, -0.5, 1.0), &mut rng))
        .collect();
    let plane: Vec<_> = (0..2000)
        .map(|_| {
            let p = Vec3::new(rng.next_f32(), rng.next_f32(), 0.0);
            record(p, &mut rng)
        })
        .collect();
    let line: Vec<_> = (0..2000)
        .map(|_| record(Vec3::new(0.0, rng.next_f32(), 0.0), &mut rng))
        .collect();
    // A lattice: many exactly equal coordinates and equal distances.
    let lattice: Vec<_> = (0..1000)
        .map(|i| {
            let p = Vec3::new((i % 10) as f32, ((i / 10) % 10) as f32, (i / 100) as f32) * 0.1;
            record(p, &mut rng)
        })
        .collect();
    let one = vec![record(Vec3::new(3.0, 4.0, 5.0), &mut rng)];
    for records in [same, plane, line, lattice, one, Vec::new()] {
        let map = PhotonMap::build(&records);
        assert_eq!(map.len(), records.len());
        check_queries(&map, 9, 40);
    }
}

/// A sharp light's primary map: a dense spot on the floor and a few photons
/// up the walls, so the root's box is the whole room and no floor subtree
/// is split on the vertical. Queries from the ceiling are the ones the
/// subtrees' own boxes prune (`photon_map::boxes`); they must find what
/// brute force finds.
#[test]
fn a_floor_spot_queried_from_the_ceiling_matches_brute_force() {
    let mut rng = Rng::new(21);
    let mut records: Vec<_> = (0..6000)
        .map(|_| {
            let (u, v) = (rng.next_f32(), rng.next_f32());
            let p = Vec3::new(0.45 + 0.1 * u * u, 0.0, 0.45 + 0.1 * v);
            record(p, &mut rng)
        })
        .collect();
    records.extend((0..60).map(|i| {
        let x = if i % 2 == 0 { 0.0 } else { 1.0 };
        let p = Vec3::new(x, rng.next_f32(), rng.next_f32());
        record(p, &mut rng)
    }));
    let map = PhotonMap::build(&records);
    let mut out = Vec::new();
    for _ in 0..40 {
        let p = Vec3::new(rng.next_f32(), 1.0, rng.next_f32());
        for k in [1, 50, 200] {
            map.nearest_k(p, k, f32::INFINITY, &mut out);
            check_knn(&map, p, k, f32::INFINITY, &out);
        }
        map.within_radius(p, 1.0, &mut out);
        check_within(&map, p, 1.0, &out);
    }
    check_queries(&map, 13, 20);
}

#[test]
fn all_equal_points_are_all_at_distance_zero() {
    let mut rng = Rng::new(4);
    let p = Vec3::new(1.0, 2.0, 3.0);
    let map = PhotonMap::build(&(0..100).map(|_| record(p, &mut rng)).collect::<Vec<_>>());
    let mut out = Vec::new();
    map.nearest_k(p, 30, 0.0, &mut out);
    assert_eq!(out.len(), 30);
    assert!(out.iter().all(|n| n.dist2 == 0.0));
    map.within_radius(p, 0.0, &mut out);
    assert_eq!(out.len(), 100);
}

#[test]
fn bad_arguments_return_nothing() {
    let map = PhotonMap::build(&random_records(100, 1));
    let mut out = vec![Neighbor {
        index: 0,
        dist2: 0.0,
    }];
    map.nearest_k(Vec3::ZERO, 0, 1.0, &mut out);
    assert!(out.is_empty());
    for r in [-1.0, f32::NAN] {
        map.nearest_k(Vec3::ZERO, 5, r, &mut out);
        assert!(out.is_empty());
        map.within_radius(Vec3::ZERO, r, &mut out);
        assert!(out.is_empty());
    }
    map.nearest_k(Vec3::new(f32::NAN, 0.0, 0.0), 5, 1.0, &mut out);
    assert!(out.is_empty());
    // A query absurdly far away still returns the k photons, finitely.
    map.nearest_k(Vec3::splat(1e30), 5, f32::INFINITY, &mut out);
    assert_eq!(out.len(), 5);
    assert!(out
        .iter()
        .all(|n| n.dist2.is_finite() || n.dist2 == f32::INFINITY));
}

#[test]
fn non_finite_records_are_skipped_and_counted() {
    let mut records = random_records(500, 2);
    records[3].position.x = f32::NAN;
    records[10].power.y = f32::INFINITY;
    records[20].direction = Vec3::ZERO;
    records[30].direction.z = f32::NAN;
    records[40].position.z = f32::NEG_INFINITY;
    let map = PhotonMap::build(&records);
    assert_eq!(map.skipped(), 5);
    assert_eq!(map.len(), 495);
    check_queries(&map, 1, 10);
}

#[test]
fn build_filtered_keeps_only_accepted_records() {
    let records = random_records(3000, 8);
    let primary = PhotonMap::build_filtered(&records, |r| r.depth == 0);
    let expected = records.iter().filter(|r| r.depth == 0).count();
    assert_eq!(primary.len(), expected);
    assert!(primary.iter().all(|r| r.depth == 0));
}

#[test]
fn map_holds_the_encoded_records() {
    let records = random_records(5000, 6);
    let map = PhotonMap::build(&records);
    let q = map.quantizer();
    let key = |r: &PhotonRecord| {
        [r.position, r.power, r.direction]
            .map(|v| v.to_array().map(f32::to_bits))
            .concat()
    };
    let mut expected: Vec<_> = records
        .iter()
        .map(|r| key(&q.decode(&q.encode(r))))
        .collect();
    let mut got: Vec<_> = map.iter().map(|r| key(&r)).collect();
    expected.sort();
    got.sort();
    assert_eq!(got, expected);
    assert_eq!(map.bytes_per_photon(), 16);
    assert!(map.memory_bytes() >= 16 * map.len());
}

#[test]
fn build_is_deterministic_across_runs_and_thread_counts() {
    // Large enough for the build to split into parallel subtrees.
    let records = random_records(100_000, 12);
    let a = PhotonMap::build(&records).checksum();
    assert_eq!(PhotonMap::build(&records).checksum(), a);
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        assert_eq!(pool.install(|| PhotonMap::build(&records)).checksum(), a);
    }
    let mut shuffled = records.clone();
    shuffled.rotate_left(777);
    assert_eq!(PhotonMap::build(&shuffled).checksum(), a);
    assert_ne!(PhotonMap::build(&records[1..]).checksum(), a);
}

#[test]
fn positions_round_trip_within_half_a_step() {
    let mut rng = Rng::new(21);
    for (min, max) in [
        (Vec3::splat(-1.0), Vec3::splat(1.0)),
        (Vec3::new(1000.0, -5.0, 3.0), Vec3::new(1010.0, 5.0, 3.0)),
        (Vec3::splat(1e-3), Vec3::splat(2e-3)),
    ] {
        let q = Quantizer::new(min, max, 1.0);
        let u = |rng: &mut Rng| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        let mut points: Vec<Vec3> = (0..20_000)
            .map(|_| min + (max - min) * u(&mut rng))
            .collect();
        points.extend([min, max, (min + max) * 0.5]);
        for p in points {
            let r = PhotonRecord {
                position: p,
                power: Vec3::ONE,
                direction: Vec3::Z,
                depth: 0,
                caustic: false,
            };
            let back = q.decode(&q.encode(&r)).position;
            for a in 0..3 {
                let bound = q.position_error_bound(p[a]);
                assert!(
                    (back[a] - p[a]).abs() <= bound,
                    "{p} -> {back}, bound {bound}"
                );
            }
        }
    }
}

#[test]
fn powers_round_trip_within_the_shared_exponent_bound() {
    let mut rng = Rng::new(22);
    for scale in [1.0f32, 1e30, 1e-30] {
        let mut powers: Vec<Vec3> = (0..20_000)
            .map(|_| {
                // Spread over 12 decades below the map's maximum.
                let m = scale * 10f32.powf(-12.0 * rng.next_f32());
                Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * m
            })
            .collect();
        powers.extend([
            Vec3::ZERO,
            Vec3::splat(scale),
            Vec3::new(scale, 0.0, 0.0),
            Vec3::new(scale * 1e-3, scale, scale * 0.999),
            Vec3::new(-1.0, scale * 0.5, 0.0),
        ]);
        let q = Quantizer::new(Vec3::ZERO, Vec3::ONE, scale);
        let big = q.power_scale();
        for p in powers {
            let r = PhotonRecord {
                position: Vec3::ZERO,
                power: p,
                direction: Vec3::Z,
                depth: 0,
                caustic: false,
            };
            let back = q.decode(&q.encode(&r)).power;
            let clamped = p.max(Vec3::ZERO);
            let max = clamped.max_element() as f64;
            for c in 0..3 {
                // Half a mantissa step of the largest channel, or of the smallest
                // exponent for very dark photons, plus f32 rounding.
                let bound = (POWER_RELATIVE_ERROR as f64 * max).max(big * 2f64.powi(-40))
                    + 2.0 * f32::EPSILON as f64 * clamped[c] as f64;
                let err = (back[c] as f64 - clamped[c] as f64).abs();
                assert!(
                    err <= bound * (1.0 + 1e-6),
                    "{p} -> {back}: {err} > {bound}"
                );
            }
        }
    }
}

#[test]
fn directions_round_trip_within_the_octahedral_bound() {
    let mut rng = Rng::new(23);
    let mut dirs: Vec<Vec3> = (0..100_000).map(|_| random_direction(&mut rng)).collect();
    for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
        dirs.extend([axis, -axis, (axis + Vec3::splat(1e-7)).normalize()]);
        dirs.extend([(-axis + Vec3::splat(1e-7)).normalize()]);
    }
    dirs.extend([
        Vec3::ONE.normalize(),
        -Vec3::ONE.normalize(),
        Vec3::new(1.0, -1.0, 0.0),
    ]);
    let q = Quantizer::new(Vec3::ZERO, Vec3::ONE, 1.0);
    let mut worst = 0.0f32;
    for d in dirs {
        let r = PhotonRecord {
            position: Vec3::ZERO,
            power: Vec3::ONE,
            direction: d * 3.0, // need not be unit
            depth: 0,
            caustic: false,
        };
        let back = q.decode(&q.encode(&r)).direction;
        assert!((back.length() - 1.0).abs() < 1e-6);
        let angle = back.dot(d.normalize()).clamp(-1.0, 1.0).acos();
        // acos loses precision near 0; the cross product's length does not.
        let angle = angle.min(back.cross(d.normalize()).length().asin());
        worst = worst.max(angle);
        assert!(angle <= MAX_DIRECTION_ERROR, "{d} -> {back}: {angle} rad");
    }
    // The bound is not absurdly loose either.
    assert!(worst > 0.2 * MAX_DIRECTION_ERROR, "worst {worst}");
    // Poles are exact.
    for d in [Vec3::Z, -Vec3::Z, Vec3::X, -Vec3::Y] {
        let r = PhotonRecord {
            position: Vec3::ZERO,
            power: Vec3::ONE,
            direction: d,
            depth: 0,
            caustic: false,
        };
        assert_eq!(q.decode(&q.encode(&r)).direction, d);
    }
}

#[test]
fn depths_round_trip_and_saturate() {
    let q = Quantizer::new(Vec3::ZERO, Vec3::ONE, 1.0);
    for depth in 0..=255u8 {
        let r = PhotonRecord {
            position: Vec3::ZERO,
            power: Vec3::ONE,
            direction: Vec3::Z,
            depth,
            caustic: false,
        };
        assert_eq!(q.decode(&q.encode(&r)).depth, depth.min(MAX_DEPTH));
    }
}
