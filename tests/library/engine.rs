//! The engine as an oracle: energy, unbiasedness of splitting, the paper's
//! Fig. 8 identity, determinism, and the extremes. Fixed seeds, small budgets.

use adaptive_pm::brdf::{Brdf, Lambert};
use adaptive_pm::embree::{thread_pool, Device};
use adaptive_pm::emitter::CosN;
use adaptive_pm::engine::{Budget, Maps, Mode, TraceConfig, Tracer};
use adaptive_pm::scene::{Emission, Light, Material, PointLight, PreparedScene, Scene};
use adaptive_pm::Error;
use glam::Vec3;

/// A closed cube [0, 1]^3 whose walls, and the light quad hung just under its
/// ceiling, all have albedo `rho`: every photon hits, and the power stored at
/// depth d has expectation `Phi * rho^d`.
fn closed_box(rho: f32, cosn: f32) -> Scene {
    let mut s = Scene::new();
    let wall = s.add_material(Material {
        name: "wall".into(),
        brdf: Brdf::Lambert(Lambert {
            albedo: Vec3::splat(rho),
        }),
        emission: None,
    });
    let light = s.add_material(Material {
        name: "light".into(),
        brdf: Brdf::Lambert(Lambert {
            albedo: Vec3::splat(rho),
        }),
        emission: Some(Emission {
            radiance: Vec3::splat(10.0),
            profile: CosN::new(cosn).unwrap(),
        }),
    });
    let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let corners = vec![
        p(0., 0., 0.),
        p(1., 0., 0.),
        p(1., 1., 0.),
        p(0., 1., 0.),
        p(0., 0., 1.),
        p(1., 0., 1.),
        p(1., 1., 1.),
        p(0., 1., 1.),
    ];
    let quads = [
        [0, 1, 2, 3],
        [4, 7, 6, 5],
        [0, 4, 5, 1],
        [3, 2, 6, 7],
        [0, 3, 7, 4],
        [1, 5, 6, 2],
    ];
    let tris = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    s.add_mesh("box", corners, tris, wall).unwrap();
    // facing down (-y) at y = 0.99
    let l = vec![
        p(0.3, 0.99, 0.3),
        p(0.3, 0.99, 0.7),
        p(0.7, 0.99, 0.7),
        p(0.7, 0.99, 0.3),
    ];
    s.add_mesh("light", l, vec![[0, 1, 2], [0, 2, 3]], light)
        .unwrap();
    s
}

fn run(
    scene: &Scene,
    cfg: &TraceConfig,
    threads: usize,
) -> (adaptive_pm::engine::TraceOutput, u64) {
    let device = Device::new().unwrap();
    let rt = scene.embree_geometry(&device).unwrap();
    let pool = thread_pool(threads).unwrap();
    pool.install(|| {
        let t = Tracer::new(PreparedScene::new(scene.clone(), &rt).unwrap());
        let out = t.trace(cfg).unwrap();
        let sum = out.clone().into_map().checksum();
        (out, sum)
    })
}

fn cfg(mode: Mode, n: u64, seed: u64) -> TraceConfig {
    let mut c = TraceConfig::new(mode, Budget::NMax(n));
    c.seed = seed;
    c
}

#[test]
fn stored_power_per_depth_is_phi_rho_to_the_d() {
    let rho = 0.5f32;
    let scene = closed_box(rho, 0.0);
    let phi = adaptive_pm::sampling::luminance(scene.lights()[0].power()) as f64;
    let n = 20_000u64;
    for mode in [Mode::Classic, Mode::Adaptive] {
        let mut c = cfg(mode, n, 3);
        c.max_depth = 6;
        let (out, _) = run(&scene, &c, 2);
        for (d, st) in out.report.depths.iter().enumerate() {
            let p = (rho as f64).powi(d as i32);
            let expect = phi * p;
            // Classic: power per photon is Phi/N at every depth (RR with r = rho keeps
            // it), and the count at depth d is a sum of N Bernoulli(rho^d): sd =
            // Phi/N * sqrt(N p (1-p)). The adaptive mode splits once and then does
            // the same roulette from one bounce later, so this bounds its sd too.
            let sd = phi / n as f64 * (n as f64 * p * (1.0 - p)).sqrt() + 1e-6 * expect;
            let got = st.stored_power_luminance;
            assert!(
                (got - expect).abs() < 5.0 * sd,
                "{mode:?} depth {d}: stored {got:.5} expected {expect:.5} (sd {sd:.5})"
            );
        }
    }
    // Density control moves power between depths (a rejected photon's power goes to
    // its neighbours) but keeps the total.
    let mut c = cfg(Mode::Density, n, 3);
    c.max_depth = 6;
    let (out, _) = run(&scene, &c, 2);
    let total: f64 = (0..=6).map(|d| phi * (rho as f64).powi(d)).sum();
    let got: f64 = out
        .report
        .depths
        .iter()
        .map(|d| d.stored_power_luminance)
        .sum();
    // sd of the total is below the sum of the per-depth sds
    let sd: f64 = (0..=6)
        .map(|d| {
            let p = (rho as f64).powi(d);
            phi / n as f64 * (n as f64 * p * (1.0 - p)).sqrt()
        })
        .sum();
    assert!(
        (got - total).abs() < 5.0 * sd + 1e-4 * total,
        "density: {got} vs {total}"
    );
    assert!(
        out.report.density_rejected > 0,
        "density control rejected nothing"
    );
}

#[test]
fn splitting_is_unbiased_floor_irradiance() {
    // Irradiance on the Cornell floor from all stored photons, classic vs adaptive,
    // each over 6 seeds; their means agree within 4 combined standard errors.
    let scene = {
        let mut s = Scene::cornell().unwrap();
        s.set_cosn(CosN::new(10.0).unwrap());
        s
    };
    let device = Device::new().unwrap();
    let rt = scene.embree_geometry(&device).unwrap();
    let tracer = Tracer::new(PreparedScene::new(scene.clone(), &rt).unwrap());
    let mut stats = Vec::new();
    for mode in [Mode::Classic, Mode::Adaptive] {
        let v: Vec<f64> = (0..6)
            .map(|seed| {
                let out = tracer.trace(&cfg(mode, 20_000, 100 + seed)).unwrap();
                out.records()
                    .iter()
                    .filter(|r| r.position.y < 0.05 && r.direction.y < 0.0)
                    .map(|r| adaptive_pm::sampling::luminance(r.power) as f64)
                    .sum::<f64>()
            })
            .collect();
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (v.len() - 1) as f64;
        stats.push((mean, (var / v.len() as f64).sqrt()));
    }
    let ((mc, sc), (ma, sa)) = (stats[0], stats[1]);
    assert!(mc > 0.0 && ma > 0.0);
    assert!(
        (mc - ma).abs() < 4.0 * (sc * sc + sa * sa).sqrt(),
        "classic {mc} ± {sc}, adaptive {ma} ± {sa}"
    );
}

#[test]
fn adaptive_first_bounce_reemits_n_max_whatever_the_exponent() {
    let n_max = 50_000u64;
    for cosn in [0.0f32, 5.0, 50.0, 200.0] {
        let scene = closed_box(0.7, cosn);
        let (out, _) = run(&scene, &cfg(Mode::Adaptive, n_max, 9), 2);
        let emitted = out.report.emitted as f64;
        let got = out.report.reemitted_first_hit as f64;
        // Each of the N_l hits makes floor(m) or floor(m)+1 children with mean
        // m = N_MAX / N_l: the total has mean N_MAX and sd <= sqrt(N_l) / 2.
        let sd = emitted.sqrt() / 2.0;
        assert!(
            (got - n_max as f64).abs() < 5.0 * sd + 1.0,
            "n={cosn}: {got} vs {n_max} (emitted {emitted})"
        );
        if cosn > 0.0 {
            assert!(
                out.report.emitted < n_max,
                "n={cosn}: a directional light emits fewer photons"
            );
        }
    }
}

#[test]
fn same_checksum_on_one_and_two_threads_and_any_batch() {
    let scene = Scene::cornell().unwrap();
    for mode in [Mode::Classic, Mode::Density, Mode::Adaptive] {
        let c = cfg(mode, 20_000, 5);
        let (a, sa) = run(&scene, &c, 1);
        let (b, sb) = run(&scene, &c, 2);
        let mut c2 = c.clone();
        c2.batch = 777;
        let (_, sc) = run(&scene, &c2, 2);
        assert_eq!(sa, sb, "{mode:?}");
        assert_eq!(sa, sc, "{mode:?} batch size");
        assert_eq!(a.report.stored, b.report.stored);
        let (_, other) = run(&scene, &cfg(mode, 20_000, 6), 2);
        assert_ne!(sa, other, "{mode:?}: the seed must matter");
    }
}

#[test]
fn quality_zero_is_an_empty_map_and_one_is_a_budget_error() {
    let scene = Scene::cornell().unwrap();
    let (out, _) = run(
        &scene,
        &TraceConfig::new(Mode::Adaptive, Budget::Quality(0.0)),
        2,
    );
    assert_eq!(out.report.emitted, 0);
    assert!(out.photons.is_empty());
    assert!(Maps::from_photons(out.photons.clone(), out.frame)
        .full
        .is_empty());

    let device = Device::new().unwrap();
    let rt = scene.embree_geometry(&device).unwrap();
    let t = Tracer::new(PreparedScene::new(scene.clone(), &rt).unwrap());
    for mode in [Mode::Classic, Mode::Adaptive] {
        let e = t
            .trace(&TraceConfig::new(mode, Budget::Quality(1.0)))
            .unwrap_err();
        match &e {
            Error::Budget {
                photons,
                needed_bytes,
                budget_bytes,
            } => {
                assert!(
                    *photons > 1_000_000_000 && needed_bytes > budget_bytes,
                    "{e}"
                );
            }
            other => panic!("expected a budget error, got {other}"),
        }
        // The library speaks of the budget, not of the command line's flag.
        assert!(e.to_string().contains("memory budget"), "{e}");
        assert!(!e.to_string().contains("--"), "{e}");
    }
    for bad in [-0.1, 1.5, f64::NAN] {
        assert!(matches!(
            t.trace(&TraceConfig::new(Mode::Adaptive, Budget::Quality(bad))),
            Err(Error::InvalidParameter { .. })
        ));
    }
}

#[test]
fn lights_a_million_times_apart_both_emit_and_a_dark_light_does_not() {
    let mut scene = closed_box(0.5, 0.0);
    scene
        .add_light(Light::Point(PointLight {
            position: Vec3::splat(0.5),
            intensity: Vec3::splat(1e-5),
        }))
        .unwrap();
    scene
        .add_light(Light::Point(PointLight {
            position: Vec3::new(0.5, 0.2, 0.5),
            intensity: Vec3::ZERO,
        }))
        .unwrap();
    for mode in [Mode::Classic, Mode::Density, Mode::Adaptive] {
        let (out, _) = run(&scene, &cfg(mode, 10_000, 1), 2);
        let per = &out.report.emitted_per_light;
        assert!(per[0] > 1000 && per[1] >= 1, "{mode:?} {per:?}");
        assert_eq!(per[2], 0, "{mode:?}: a zero-power light emits nothing");
    }
}

#[test]
fn scene_without_light_is_an_error() {
    let mut scene = closed_box(0.5, 0.0);
    scene.clear_lights();
    let device = Device::new().unwrap();
    let rt = scene.embree_geometry(&device).unwrap();
    let e = Tracer::new(PreparedScene::new(scene.clone(), &rt).unwrap())
        .trace(&cfg(Mode::Classic, 100, 1))
        .unwrap_err();
    assert!(matches!(e, Error::InvalidScene(_)), "{e}");
}

#[test]
fn albedo_zero_and_one_and_extreme_exponents_terminate() {
    for (rho, cosn) in [(0.0f32, 0.0f32), (1.0, 0.0), (0.5, 1e4)] {
        let scene = closed_box(rho, cosn);
        for mode in [Mode::Classic, Mode::Density, Mode::Adaptive] {
            let mut c = cfg(mode, 5_000, 2);
            c.max_depth = 8;
            let (out, _) = run(&scene, &c, 2);
            let r = &out.report;
            assert!(r.depths.len() <= 9, "{mode:?} rho={rho}: depth bound");
            if rho == 0.0 {
                assert_eq!(
                    r.stored, r.stored_primary,
                    "{mode:?}: albedo 0 stores first hits only"
                );
            }
            if rho == 1.0 && mode == Mode::Classic {
                // no absorption: every photon survives to the depth limit
                assert_eq!(r.depths[8].hits, r.emitted);
            }
            assert!(out
                .records()
                .iter()
                .all(|p| p.power.is_finite() && p.position.is_finite()));
        }
    }
}

#[test]
fn the_memory_budget_bounds_a_wave_of_splitting() {
    // A cos^200 light at N_MAX = 1e6 emits ~17 000 photons that would each
    // split ~60-fold at the first hit: 1e6 children. With room for 800 000
    // stored photons' worth (a pending path costs three: 48 bytes against
    // 16), the wave's splitting is scaled down to fit, and says so.
    let mut scene = Scene::cornell().unwrap();
    scene.set_cosn(CosN::new(200.0).unwrap());
    let max_photons = 800_000u64;
    let mut c = cfg(Mode::Adaptive, 1_000_000, 4);
    c.memory_budget = Some(max_photons * adaptive_pm::engine::tracer::BYTES_PER_STORED_PHOTON);
    let (out, _) = run(&scene, &c, 2);
    let r = &out.report;
    assert!(r.budget_bound);
    assert!(r.stored <= max_photons, "{} stored", r.stored);
    // the children of the first wave fit in half the budget, less what it held
    assert!(
        r.reemitted_first_hit <= max_photons / 2,
        "{}",
        r.reemitted_first_hit
    );
    // splitting still happened, scaled, not switched off
    assert!(
        r.split_rate_by_depth[0] > 1.5,
        "{:?}",
        r.split_rate_by_depth
    );
    // and the power is still right: the same first-bounce power as an unbounded run
    let mut free = c.clone();
    free.memory_budget = None;
    let (f, _) = run(&scene, &free, 2);
    let (a, b) = (
        r.depths[1].stored_power_luminance,
        f.report.depths[1].stored_power_luminance,
    );
    assert!((a - b).abs() < 0.05 * b, "depth-1 power {a} vs {b}");
}
