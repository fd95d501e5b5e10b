//! Importance in the adaptive counts (`TraceConfig::importance`): the
//! map's expected power where it is read is classic's, a region no ray
//! sees stores nothing, runs are the same over threads and shards, and
//! only the adaptive mode takes it.

use adaptive_pm::brdf::{Brdf, Lambert};
use adaptive_pm::embree::{thread_pool, Device};
use adaptive_pm::emitter::CosN;
use adaptive_pm::engine::{Budget, Mode, Shard, TraceConfig, TraceOutput, Tracer};
use adaptive_pm::importance::ImportanceConfig;
use adaptive_pm::photon_map::PhotonRecord;
use adaptive_pm::scene::{Camera, Emission, Material, Scene};
use adaptive_pm::Error;
use glam::Vec3;

use crate::common;

fn material(s: &mut Scene, albedo: f32, emission: Option<f32>) -> usize {
    s.add_material(Material {
        name: format!("m{albedo}"),
        brdf: Brdf::Lambert(Lambert {
            albedo: Vec3::splat(albedo),
        }),
        emission: emission.map(|e| Emission::new(Vec3::splat(e), CosN::new(0.0).unwrap())),
    })
}

fn quad(s: &mut Scene, v: [Vec3; 4], material: usize) {
    s.add_mesh("quad", v.to_vec(), vec![[0, 1, 2], [0, 2, 3]], material)
        .unwrap();
}

/// A closed cube of side `size` at `lo` with a lamp facing down inside,
/// at 85 % of its height.
fn lit_cube(s: &mut Scene, lo: Vec3, size: f32, wall: usize, lamp: usize) {
    let c: Vec<Vec3> = (0..8)
        .map(|i| lo + size * Vec3::new((i & 1) as f32, (i >> 1 & 1) as f32, (i >> 2) as f32))
        .collect();
    for f in [
        [0, 1, 3, 2],
        [4, 6, 7, 5],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 5, 7, 3],
    ] {
        quad(s, f.map(|k| c[k]), wall);
    }
    let light = [(0.3, 0.3), (0.3, 0.7), (0.7, 0.7), (0.7, 0.3)]
        .map(|(x, z)| lo + size * Vec3::new(x, 0.85, z));
    quad(s, light, lamp);
}

/// A lit room the camera looks into (at its back wall, z = 1), and beside
/// it a second lit room, closed, that no ray of the camera's enters.
fn two_rooms() -> Scene {
    let mut s = Scene::new();
    let (wall, lamp) = (
        material(&mut s, 0.6, None),
        material(&mut s, 0.0, Some(5.0)),
    );
    lit_cube(&mut s, Vec3::ZERO, 1.0, wall, lamp);
    lit_cube(&mut s, Vec3::new(2.0, 0.0, 0.0), 0.5, wall, lamp);
    let eye = Vec3::new(0.5, 0.5, 0.05);
    s.set_camera(Camera::look_at(eye, Vec3::new(0.5, 0.45, 1.0), Vec3::Y, 50.0).unwrap())
        .unwrap();
    s
}

fn importance() -> ImportanceConfig {
    ImportanceConfig {
        width: 32,
        height: 32,
        spp: 2,
        ..ImportanceConfig::default()
    }
}

fn config(mode: Mode, n: u64, seed: u64, importance: bool) -> TraceConfig {
    let mut c = TraceConfig::new(mode, Budget::NMax(n));
    c.seed = seed;
    c.importance = importance.then(self::importance);
    c
}

fn trace(
    tracer: &Tracer<adaptive_pm::embree::CommittedScene>,
    c: &TraceConfig,
    threads: usize,
) -> TraceOutput {
    thread_pool(threads)
        .unwrap()
        .install(|| tracer.trace(c))
        .unwrap()
}

fn tracer(scene: &Scene) -> Tracer<adaptive_pm::embree::CommittedScene> {
    Tracer::new(scene.clone().commit(&Device::new().unwrap()).unwrap())
}

#[test]
fn a_closed_room_no_ray_sees_stores_no_photons() {
    let t = tracer(&two_rooms());
    let in_shut_room = |r: &PhotonRecord| r.position.x > 1.5;
    let plain = trace(&t, &config(Mode::Adaptive, 4000, 3, false), 2);
    assert!(plain.records().iter().any(in_shut_room));
    let seen = trace(&t, &config(Mode::Adaptive, 4000, 3, true), 2);
    let records = seen.records();
    assert!(!records.is_empty());
    assert_eq!(records.iter().filter(|r| in_shut_room(r)).count(), 0);
    let report = seen.report.importance.unwrap();
    assert!(report.unread > 0);
    // The shut room's light: every pilot photon lands where nothing is
    // seen, so it emits at the floor's share of the paper's count.
    assert_eq!(
        report.emission_alpha_i[1],
        adaptive_pm::importance::ALPHA_I_FLOOR
    );
    assert!(seen.report.emitted_per_light[1] < plain.report.emitted_per_light[1] / 8);
}

/// Luminance of the power stored within `radius` of `p` by photons that
/// arrived on the side of `n`.
fn power_near(records: &[PhotonRecord], p: Vec3, n: Vec3, radius: f32) -> f64 {
    records
        .iter()
        .filter(|r| (r.position - p).length() < radius && r.direction.dot(n) < 0.0)
        .map(|r| f64::from(r.power.x))
        .sum()
}

#[test]
fn importance_keeps_classic_power_where_it_is_read() {
    let scene = two_rooms();
    let t = tracer(&scene);
    // Points of the back wall in view, from inside the room.
    let points = [
        (Vec3::new(0.5, 0.5, 1.0), -Vec3::Z),
        (Vec3::new(0.3, 0.3, 1.0), -Vec3::Z),
        (Vec3::new(0.7, 0.6, 1.0), -Vec3::Z),
    ];
    let shards = 8u32;
    let measure = |importance: bool, mode: Mode| -> Vec<common::MeanVar> {
        let mut per_point = vec![common::MeanVar::default(); points.len()];
        for i in 0..shards {
            let mut c = config(mode, 16_000, common::seed(41), importance);
            c.shard = Shard::new(i, shards).unwrap();
            let records = trace(&t, &c, 2).records();
            for (m, &(p, n)) in per_point.iter_mut().zip(&points) {
                m.push(power_near(&records, p, n, 0.1));
            }
        }
        per_point
    };
    let classic = measure(false, Mode::Classic);
    let seen = measure(true, Mode::Adaptive);
    for (k, (c, s)) in classic.iter().zip(&seen).enumerate() {
        let sigma = (c.std_error().powi(2) + s.std_error().powi(2)).sqrt();
        assert!(c.mean() > 0.0 && sigma > 0.0);
        common::assert_sigmas(
            &format!("power near point {k}, importance - classic"),
            s.mean() - c.mean(),
            sigma,
            common::MIN_SIGMAS,
        );
    }
}

/// A record's bits: position, power, direction, depth.
type RecordKey = ([u32; 3], [u32; 3], [u32; 3], u8);

fn record_keys(records: &[PhotonRecord]) -> Vec<RecordKey> {
    let b = |v: Vec3| v.to_array().map(f32::to_bits);
    let mut k: Vec<_> = records
        .iter()
        .map(|r| (b(r.position), b(r.power), b(r.direction), r.depth))
        .collect();
    k.sort_unstable();
    k
}

#[test]
fn importance_runs_are_the_same_over_threads_and_shards() {
    let t = tracer(&Scene::cornell().unwrap());
    let base = config(Mode::Adaptive, 3000, 5, true);
    let one = trace(&t, &base, 1);
    let two = trace(&t, &base, 2);
    assert_eq!(one.clone().into_map().checksum(), two.into_map().checksum());
    let mut all = Vec::new();
    for i in 0..3 {
        let mut c = base.clone();
        c.shard = Shard::new(i, 3).unwrap();
        all.extend(trace(&t, &c, 2).records());
    }
    assert!(record_keys(&all) == record_keys(&one.records()));
    // Importance changes the run.
    let paper = trace(&t, &config(Mode::Adaptive, 3000, 5, false), 2);
    assert_ne!(paper.into_map().checksum(), one.into_map().checksum());
}

#[test]
fn only_the_adaptive_mode_takes_importance() {
    for mode in [Mode::Classic, Mode::Density] {
        let e = config(mode, 100, 1, true).validate().unwrap_err();
        assert!(matches!(e, Error::InvalidParameter { .. }), "{e}");
    }
    let mut c = config(Mode::Adaptive, 100, 1, true);
    if let Some(i) = c.importance.as_mut() {
        i.shard = Shard::new(0, 2).unwrap();
    }
    assert!(c.validate().is_err());
    assert!(config(Mode::Adaptive, 100, 1, true).validate().is_ok());
}

#[test]
fn shards_with_and_without_importance_never_merge() {
    use adaptive_pm::photon_file::settings_hash;
    let paper = config(Mode::Adaptive, 100, 1, false);
    let seen = config(Mode::Adaptive, 100, 1, true);
    assert_ne!(settings_hash(&paper), settings_hash(&seen));
    let mut other = seen.clone();
    if let Some(i) = other.importance.as_mut() {
        i.later_bounces += 1;
    }
    assert_ne!(settings_hash(&other), settings_hash(&seen));
    // The paper's files keep the hash they always had.
    assert_eq!(
        settings_hash(&paper),
        settings_hash(&TraceConfig {
            seed: 1,
            ..TraceConfig::new(Mode::Adaptive, Budget::NMax(100))
        })
    );
}

/// Two unit rooms side by side, joined by a gap 0.1 wide in their shared
/// wall (x = 1); the light in room B, the camera in room A looking at its
/// back wall, away from the gap.
fn rooms_with_a_gap() -> Scene {
    let mut s = Scene::new();
    let (wall, lamp) = (
        material(&mut s, 0.6, None),
        material(&mut s, 0.0, Some(20.0)),
    );
    let v = Vec3::new;
    // The outer box [0, 2] x [0, 1] x [0, 1].
    for q in [
        [v(0., 0., 0.), v(2., 0., 0.), v(2., 0., 1.), v(0., 0., 1.)],
        [v(0., 1., 0.), v(0., 1., 1.), v(2., 1., 1.), v(2., 1., 0.)],
        [v(0., 0., 0.), v(0., 1., 0.), v(2., 1., 0.), v(2., 0., 0.)],
        [v(0., 0., 1.), v(2., 0., 1.), v(2., 1., 1.), v(0., 1., 1.)],
        [v(0., 0., 0.), v(0., 0., 1.), v(0., 1., 1.), v(0., 1., 0.)],
        [v(2., 0., 0.), v(2., 1., 0.), v(2., 1., 1.), v(2., 0., 1.)],
    ] {
        quad(&mut s, q, wall);
    }
    // The shared wall, but for a gap z in [0.45, 0.55] below y = 0.8.
    let piece =
        |z0: f32, z1: f32, y0: f32| [v(1., y0, z0), v(1., 1., z0), v(1., 1., z1), v(1., y0, z1)];
    for q in [
        piece(0.0, 0.45, 0.0),
        piece(0.55, 1.0, 0.0),
        piece(0.45, 0.55, 0.8),
    ] {
        quad(&mut s, q, wall);
    }
    let light = [(1.3, 0.3), (1.3, 0.7), (1.7, 0.7), (1.7, 0.3)].map(|(x, z)| v(x, 0.95, z));
    quad(&mut s, light, lamp);
    let eye = v(0.5, 0.5, 0.05);
    s.set_camera(Camera::look_at(eye, v(0.5, 0.45, 1.0), Vec3::Y, 50.0).unwrap())
        .unwrap();
    s
}

/// Not a check: the noise of the power stored near seen points, per mode,
/// at one `N_MAX`, scaled to equal stored photons (memory). Run with
/// `cargo test --test library importance_counts::measure_rooms_with_a_gap -- --ignored --nocapture`.
#[test]
#[ignore]
fn measure_rooms_with_a_gap() {
    let t = tracer(&rooms_with_a_gap());
    let points = [
        (Vec3::new(0.5, 0.5, 1.0), -Vec3::Z),
        (Vec3::new(0.3, 0.3, 1.0), -Vec3::Z),
        (Vec3::new(0.7, 0.6, 1.0), -Vec3::Z),
    ];
    let shards = 16u32;
    let small = Some(importance());
    let default = Some(ImportanceConfig::default());
    for (mode, imp) in [
        (Mode::Classic, None),
        (Mode::Adaptive, None),
        (Mode::Adaptive, small),
        (Mode::Adaptive, default),
    ] {
        let mut per_point = vec![common::MeanVar::default(); points.len()];
        let (mut stored, mut seconds) = (0u64, 0.0f64);
        for i in 0..shards {
            let mut c = config(mode, 64_000, 7, false);
            c.shard = Shard::new(i, shards).unwrap();
            c.importance = imp;
            let out = trace(&t, &c, 2);
            stored += out.report.stored;
            seconds +=
                out.report.trace_s + out.report.importance.as_ref().map_or(0.0, |r| r.pass_s);
            let records = out.records();
            for (m, &(p, n)) in per_point.iter_mut().zip(&points) {
                m.push(power_near(&records, p, n, 0.1));
            }
        }
        let rel: Vec<f64> = per_point.iter().map(|m| m.std_error() / m.mean()).collect();
        let mean_rel = rel.iter().sum::<f64>() / rel.len() as f64;
        eprintln!(
            "{mode} importance {:?}: power near points {:?}",
            imp.map(|i| (i.width, i.height, i.spp)),
            per_point.iter().map(|m| m.mean()).collect::<Vec<_>>(),
        );
        // The table row of docs/method.md ("The importance pass").
        let name = match imp {
            None => mode.to_string(),
            Some(i) => format!(
                "{mode} + importance, pass {} x {} x {}",
                i.width, i.height, i.spp
            ),
        };
        println!(
            "| {name} | {stored} | {mean_rel:.3} | {:.0} | {seconds:.2} | {:.3} |",
            mean_rel * (stored as f64).sqrt(),
            mean_rel * seconds.sqrt(),
        );
    }
}
