//! The engine as an oracle: energy, unbiasedness of splitting, the paper's
//! Fig. 8 identity, determinism, and the extremes. Small budgets.
//!
//! Statistical checks take their seeds through `common::seed` and measure
//! their own noise: a run is traced as shards (independent batches of its
//! emitted photons) and sigma is the shards' spread, or the noise comes from
//! the run's own per-hit counts. The other tests are exact (checksums,
//! counts, errors) and keep fixed seeds.

use adaptive_pm::brdf::{Brdf, Lambert};
use adaptive_pm::embree::{thread_pool, Device};
use adaptive_pm::emitter::CosN;
use adaptive_pm::engine::{Budget, Maps, Mode, Shard, TraceConfig, Tracer};
use adaptive_pm::photon_map::photon::POWER_RELATIVE_ERROR;
use adaptive_pm::scene::{Emission, Light, Material, PointLight, PreparedScene, Scene};
use adaptive_pm::Error;
use glam::Vec3;

use crate::common;

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
        emission: Some(Emission::new(Vec3::splat(10.0), CosN::new(cosn).unwrap())),
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

/// The shards `0..count` of the run `base`: disjoint sets of emitted photons
/// whose random numbers come from their own keys, so shards are independent,
/// identically distributed batches of one run (their union is the whole run,
/// bit for bit: `shards::merged_shards_reproduce_the_single_run_checksum`).
fn shards<C: adaptive_pm::raycast::RayCaster>(
    tracer: &Tracer<C>,
    base: &TraceConfig,
    count: u32,
) -> Vec<adaptive_pm::engine::TraceOutput> {
    (0..count)
        .map(|i| {
            let mut c = base.clone();
            c.shard = Shard::new(i, count).unwrap();
            tracer.trace(&c).unwrap()
        })
        .collect()
}

/// The whole run's total of a per-shard quantity, and its standard error
/// measured from the spread of the shards (batch means): `count` times the
/// standard error of the shards' mean. Shard sizes differ by at most one
/// photon, which only adds to the measured spread.
fn shard_total(xs: impl IntoIterator<Item = f64>) -> (f64, f64) {
    let m = common::MeanVar::of(xs);
    let b = m.count() as f64;
    (m.mean() * b, m.std_error() * b)
}

/// Stored luminance power at depth `d` of a run (0 when no photon got there).
fn power_at(out: &adaptive_pm::engine::TraceOutput, d: usize) -> f64 {
    out.report
        .depths
        .get(d)
        .map_or(0.0, |s| s.stored_power_luminance)
}

#[test]
fn stored_power_per_depth_is_phi_rho_to_the_d() {
    let rho = 0.5f32;
    let scene = closed_box(rho, 0.0);
    let phi = adaptive_pm::sampling::luminance(scene.lights()[0].power()) as f64;
    let n = 20_000u64;
    let device = Device::new().unwrap();
    let rt = scene.embree_geometry(&device).unwrap();
    let tracer = Tracer::new(PreparedScene::new(scene.clone(), &rt).unwrap());
    let pool = thread_pool(2).unwrap();
    // The run as 80 shards of 250 emitted photons: sigma of each depth's
    // total is measured from the shards' spread (79 degrees of freedom).
    const SHARDS: u32 = 80;
    let mut classic_total = 0.0;
    for mode in [Mode::Classic, Mode::Adaptive] {
        let mut c = cfg(mode, n, common::seed(3));
        c.max_depth = 6;
        let outs = pool.install(|| shards(&tracer, &c, SHARDS));
        for d in 0..=6usize {
            let expect = phi * (rho as f64).powi(d as i32);
            let (got, sigma) = shard_total(outs.iter().map(|o| power_at(o, d)));
            if mode == Mode::Classic {
                classic_total += got;
            }
            // Systematic: a stored photon's power is kept to a 9-bit mantissa
            // (POWER_RELATIVE_ERROR); photons of one depth here all carry the
            // same power, so their rounding errors do not average out.
            let quantised = POWER_RELATIVE_ERROR as f64 * expect;
            if sigma == 0.0 {
                // No noise at all: depth 0 (every photon hits the closed box
                // and stores Phi/N), and the adaptive mode's depth 1 (exactly
                // one child per first hit, m = N_MAX / N_l = 1, no roulette).
                assert!(
                    (got - expect).abs() <= quantised + 1e-9 * expect,
                    "{mode:?} depth {d}: stored {got} expected {expect} exactly"
                );
            } else {
                // 5 sigma: 12 checks, t with 79 degrees of freedom.
                common::assert_within_noise(
                    &format!("{mode:?} depth {d} stored power"),
                    got - expect,
                    sigma,
                    5.0 * sigma + quantised,
                );
            }
        }
    }
    // Density control traces the classic mode's paths (a photon's random
    // numbers come from its key) and moves a rejected photon's power to its
    // neighbours: its total is the classic run's total of the same seed, up
    // to the power quantisation of the stored photons (deterministic).
    let mut c = cfg(Mode::Density, n, common::seed(3));
    c.max_depth = 6;
    let out = pool.install(|| tracer.trace(&c)).unwrap();
    let got: f64 = out
        .report
        .depths
        .iter()
        .map(|d| d.stored_power_luminance)
        .sum();
    eprintln!(
        "density total - classic total: {:+.2e} relative",
        got / classic_total - 1.0
    );
    assert!(
        (got - classic_total).abs() <= POWER_RELATIVE_ERROR as f64 * classic_total,
        "density: {got} vs the classic run's {classic_total}"
    );
    assert!(
        out.report.density_rejected > 0,
        "density control rejected nothing"
    );
}

#[test]
fn splitting_is_unbiased_floor_irradiance() {
    // Irradiance on the Cornell floor from all stored photons, classic vs
    // adaptive, each one run of N_MAX = 120 000 traced as 60 shards; sigma of
    // each total is measured from its shards' spread, and the totals agree
    // within 4 combined sigmas.
    let scene = {
        let mut s = Scene::cornell().unwrap();
        s.set_cosn(CosN::new(10.0).unwrap());
        s
    };
    let device = Device::new().unwrap();
    let rt = scene.embree_geometry(&device).unwrap();
    let tracer = Tracer::new(PreparedScene::new(scene.clone(), &rt).unwrap());
    let pool = thread_pool(2).unwrap();
    let floor = |out: &adaptive_pm::engine::TraceOutput| {
        out.records()
            .iter()
            .filter(|r| r.position.y < 0.05 && r.direction.y < 0.0)
            .map(|r| adaptive_pm::sampling::luminance(r.power) as f64)
            .sum::<f64>()
    };
    let mut stats = Vec::new();
    for (k, mode) in [Mode::Classic, Mode::Adaptive].into_iter().enumerate() {
        let c = cfg(mode, 120_000, common::seed(100 + k as u64));
        let outs = pool.install(|| shards(&tracer, &c, 60));
        stats.push(shard_total(outs.iter().map(floor)));
    }
    let ((mc, sc), (ma, sa)) = (stats[0], stats[1]);
    assert!(mc > 0.0 && ma > 0.0);
    common::assert_sigmas(
        "classic vs adaptive floor power",
        mc - ma,
        (sc * sc + sa * sa).sqrt(),
        4.0,
    );
}

#[test]
fn adaptive_first_bounce_reemits_n_max_whatever_the_exponent() {
    let n_max = 50_000u64;
    for cosn in [0.0f32, 5.0, 50.0, 200.0] {
        let scene = closed_box(0.7, cosn);
        let (out, _) = run(&scene, &cfg(Mode::Adaptive, n_max, common::seed(9)), 2);
        let emitted = out.report.emitted;
        let got = out.report.reemitted_first_hit;
        // Every one of the N_l photons hits a wall (alpha_D = 1) and makes
        // floor(m) or floor(m) + 1 children, m = N_MAX / N_l: the total has
        // mean N_MAX. Its noise is measured from those per-hit counts: with
        // `extra` hits of floor(m) + 1, their variance is f (1 - f), f =
        // extra / N_l, and the total's sigma is sqrt(N_l f (1 - f)).
        let base = n_max / emitted;
        let extra = got
            .checked_sub(base * emitted)
            .filter(|&e| e <= emitted)
            .unwrap_or_else(|| panic!("n={cosn}: {got} children of {emitted} hits"));
        let f = extra as f64 / emitted as f64;
        let sigma = (emitted as f64 * f * (1.0 - f)).sqrt();
        // Systematic: m comes from alpha_E in f32 (relative 1e-7, 0.005
        // children here); one child is a generous allowance.
        let dev = got as f64 - n_max as f64;
        if sigma == 0.0 {
            // Every hit made the same number of children (cos^0: m = 1).
            assert!(dev.abs() <= 1.0, "n={cosn}: {got} vs {n_max}");
        } else {
            common::assert_within_noise(
                &format!("cos^{cosn} children of the first hits"),
                dev,
                sigma,
                5.0 * sigma + 1.0,
            );
        }
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
    // Refused when prepared: the tracer and the renderer trust a prepared scene.
    let e = PreparedScene::new(scene.clone(), &rt).unwrap_err();
    assert!(matches!(e, Error::InvalidScene(_)), "{e}");
    let e = scene.commit(&device).unwrap_err();
    assert!(e.to_string().contains("no light"), "{e}");
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
    let mut c = cfg(Mode::Adaptive, 1_000_000, common::seed(4));
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
    // And the power is still right: the first-bounce power of a bound run
    // is that of an unbounded one. Measured on the run as 24 shards, each a
    // bound run of its own (a 24th of the emitted photons and of the budget,
    // so its splitting is scaled alike), paired with the same shard
    // unbounded (same seed: the same emitted photons and first hits). Sigma
    // of the summed difference is the spread of the 24 paired differences.
    const SHARDS: u32 = 24;
    let device = Device::new().unwrap();
    let rt = scene.embree_geometry(&device).unwrap();
    let tracer = Tracer::new(PreparedScene::new(scene.clone(), &rt).unwrap());
    let pool = thread_pool(2).unwrap();
    let mut small = c.clone();
    small.memory_budget = c.memory_budget.map(|b| b / SHARDS as u64);
    let mut free = c.clone();
    free.memory_budget = None;
    let bound = pool.install(|| shards(&tracer, &small, SHARDS));
    let unbound = pool.install(|| shards(&tracer, &free, SHARDS));
    assert!(bound.iter().all(|o| o.report.budget_bound));
    assert!(unbound.iter().all(|o| !o.report.budget_bound));
    let (diff, sigma) = shard_total(
        bound
            .iter()
            .zip(&unbound)
            .map(|(a, b)| power_at(a, 1) - power_at(b, 1)),
    );
    let (b, _) = shard_total(unbound.iter().map(|o| power_at(o, 1)));
    eprintln!(
        "depth-1 power: bound - unbound = {diff:.4e} of {b:.4e} ({:.2} %)",
        100.0 * diff / b
    );
    // Systematic: the children's powers are kept to a 9-bit mantissa
    // (POWER_RELATIVE_ERROR), in each run; 5 sigma: t with 23 degrees of freedom.
    common::assert_within_noise(
        "depth-1 power bound vs unbounded",
        diff,
        sigma,
        5.0 * sigma + 2.0 * POWER_RELATIVE_ERROR as f64 * b,
    );
}
