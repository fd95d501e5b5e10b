//! Directional lights (glTF `directional`, Blender's Sun) as oracles: the
//! disc the scene fits (power `E pi r^2`, exact, following the geometry),
//! photons that all travel the light's way, the photon map's irradiance on
//! a floor against `E cos(theta)` within the noise the test measures, the
//! renderer's, the path tracer's and the quadrature's direct light (a delta
//! light: exact), its shadow, the loader, and the refusals.

use adaptive_pm::analysis::AnalysisParams;
use adaptive_pm::brdf::{Brdf, Lambert};
use adaptive_pm::embree::{thread_pool, Device, EmbreeScene};
use adaptive_pm::engine::{Budget, Mode, TraceConfig, TraceOutput, Tracer};
use adaptive_pm::photon_map::photon::MAX_DIRECTION_ERROR;
use adaptive_pm::photon_map::{PhotonMap, PhotonRecord};
use adaptive_pm::raycast::Ray;
use adaptive_pm::render::{
    irradiance_estimate, quadrature_irradiance, unshadowed_irradiance, LightSampler, Lookup,
    PathPart, PathTracer,
};
use adaptive_pm::rng::Rng;
use adaptive_pm::scene::{DirectionalLight, Light, Material, Scene};
use adaptive_pm::Error;
use glam::Vec3;
use std::f32::consts::PI;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::common;

/// The Sun's irradiance, as `tests/scenes/sun_floor.gltf` has it.
const E: Vec3 = Vec3::new(2.0, 1.9, 1.8);
const ALBEDO: f32 = 0.8;

/// 30 degrees from the vertical, towards -z.
fn sun_direction() -> Vec3 {
    let t = 30f32.to_radians();
    Vec3::new(0.0, -t.cos(), -t.sin())
}

fn cos_theta() -> f32 {
    30f32.to_radians().cos()
}

fn sun_floor_file() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenes/sun_floor.gltf")
}

fn white(s: &mut Scene) -> usize {
    s.add_material(Material {
        name: "white".into(),
        brdf: Lambert::new(Vec3::splat(ALBEDO)).unwrap().into(),
        emission: None,
    })
}

/// A 2 x 2 white floor at y = 0 facing +y, lit by the Sun alone. The light
/// comes first: its disc must follow the floor added after it.
fn sunlit_floor() -> Scene {
    let mut s = Scene::new();
    let sun = DirectionalLight::new(sun_direction(), E);
    s.add_light(Light::Directional(sun)).unwrap();
    let m = white(&mut s);
    let positions = vec![
        Vec3::new(-1.0, 0.0, -1.0),
        Vec3::new(1.0, 0.0, -1.0),
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::new(-1.0, 0.0, 1.0),
    ];
    s.add_mesh("floor", positions, vec![[0, 3, 2], [0, 2, 1]], m)
        .unwrap();
    s
}

fn sun_of(s: &Scene) -> DirectionalLight {
    s.lights()
        .iter()
        .find_map(|l| match l {
            Light::Directional(d) => Some(*d),
            _ => None,
        })
        .expect("the scene has a directional light")
}

fn close(a: Vec3, b: Vec3, rel: f32) -> bool {
    (a - b).abs().max_element() <= rel * b.abs().max_element()
}

fn trace(prepared: &Arc<EmbreeScene>, mode: Mode, n_max: u64, seed: u64) -> TraceOutput {
    let mut cfg = TraceConfig::new(mode, Budget::NMax(n_max));
    cfg.seed = seed;
    Tracer::new(Arc::clone(prepared)).trace(&cfg).unwrap()
}

#[test]
fn the_power_is_e_pi_r_squared_over_the_geometry_as_it_grows() {
    let mut s = sunlit_floor();
    let sun = sun_of(&s);
    assert_eq!(sun.scene_centre(), Vec3::ZERO);
    assert_eq!(sun.scene_radius(), 2f32.sqrt());
    assert!(close(sun.power(), E * (2.0 * PI), 1e-6), "{}", sun.power());
    // A mesh added afterwards: the disc covers it too, no stale radius.
    let m = white(&mut s);
    let far = vec![
        Vec3::new(9.0, 0.0, 0.0),
        Vec3::new(9.0, 1.0, 0.0),
        Vec3::new(9.0, 0.0, 1.0),
    ];
    s.add_mesh("far", far, vec![[0, 1, 2]], m).unwrap();
    let grown = sun_of(&s);
    assert_eq!(grown.scene_centre(), Vec3::new(4.0, 0.5, 0.0));
    let r = (25.0f32 + 0.25 + 1.0).sqrt();
    assert!((grown.scene_radius() - r).abs() <= 1e-6 * r);
    let want = E * (PI * r * r);
    assert!(close(s.lights()[0].power(), want, 1e-6));
}

#[test]
fn photons_leave_the_disc_along_the_light_and_are_deterministic() {
    let scene = sunlit_floor();
    let sun = sun_of(&scene);
    let (c, r, w) = (sun.scene_centre(), sun.scene_radius(), sun.direction());
    let mut rng = Rng::new(common::seed(3));
    for _ in 0..10_000 {
        let e = scene.lights()[0].sample(rng.next_f32(), rng.next_2d(), rng.next_2d());
        assert_eq!(e.direction, w);
        assert_eq!(e.weight, Vec3::ONE);
        // Upstream of every point of the bounding sphere, within the disc.
        let rel = e.origin - c;
        assert!(rel.dot(w) < -r, "{} starts inside the sphere", e.origin);
        assert!((rel - w * rel.dot(w)).length() <= r * (1.0 + 1e-5));
    }
    let device = Device::new().unwrap();
    let prepared = Arc::new(scene.commit(&device).unwrap());
    let first = trace(&prepared, Mode::Classic, 20_000, 7);
    let primary: Vec<PhotonRecord> = first
        .records()
        .into_iter()
        .filter(|p| p.depth == 0)
        .collect();
    assert!(primary.len() > 5_000, "{} first hits", primary.len());
    for p in &primary {
        let angle = p.direction.dot(w).clamp(-1.0, 1.0).acos();
        assert!(
            angle <= MAX_DIRECTION_ERROR,
            "{} is {angle} rad off",
            p.direction
        );
    }
    // The same seed gives the same map, on one thread or two; another seed another.
    let checksum = |out: TraceOutput| out.into_map().checksum();
    let want = checksum(first);
    for threads in [1, 2] {
        let pool = thread_pool(threads).unwrap();
        let again = pool.install(|| trace(&prepared, Mode::Classic, 20_000, 7));
        assert_eq!(checksum(again), want, "{threads} threads");
    }
    assert_ne!(checksum(trace(&prepared, Mode::Classic, 20_000, 8)), want);
}

/// The adaptive counts: `alpha_A = 1` (no area) and `alpha_D = alpha_min` (a
/// delta in direction).
#[test]
fn the_adaptive_mode_gives_the_sun_alpha_min() {
    let device = Device::new().unwrap();
    let prepared = Arc::new(sunlit_floor().commit(&device).unwrap());
    let n_max = 1_000_000;
    let out = trace(&prepared, Mode::Adaptive, n_max, 1);
    let plan = out.plans[0];
    let alpha_min = AnalysisParams::default().alpha_min;
    assert_eq!(
        (plan.alpha_e, plan.alpha_a, plan.alpha_d),
        (1.0, 1.0, alpha_min)
    );
    let expected = (f64::from(alpha_min) * n_max as f64).round() as u64;
    assert_eq!(plan.photons, expected);
    assert_eq!(out.report.emitted_per_light, vec![expected]);
}

/// The share of disc photons that reach the floor is its projected area over
/// the disc's, `A cos(theta) / (pi r^2)`: the count is binomial, and sigma
/// is `sqrt(N p (1 - p))` at the share the run measured.
#[test]
fn the_floor_intercepts_its_projected_share_of_the_disc() {
    let device = Device::new().unwrap();
    let scene = sunlit_floor();
    let r = sun_of(&scene).scene_radius();
    let prepared = Arc::new(scene.commit(&device).unwrap());
    let n = 200_000u64;
    let out = trace(&prepared, Mode::Classic, n, common::seed(21));
    let hits = out.report.stored_primary as f64;
    let p = f64::from(4.0 * cos_theta() / (PI * r * r));
    let measured = hits / n as f64;
    let sigma = (n as f64 * measured * (1.0 - measured)).sqrt();
    common::assert_sigmas("first hits on the floor", hits - n as f64 * p, sigma, 4.0);
}

/// The floor's irradiance read from the depth-0 photons (k nearest, cone
/// filter) at a 5 x 5 grid of points 0.3 apart (over four kernel radii)
/// equals `E cos(theta)` everywhere: the density is uniform, so the kernel
/// has no bias. Sigma as in `render::primary_map_irradiance_matches_the_light_quadrature`:
/// the photons split into two halves of twice the power, each read with
/// `k / 2` neighbours; `s^2 = mean ((e1 - e2) / (2 E))^2` over the points.
/// The mean ratio within 4 `s / sqrt(M)`; the worst point's log ratio
/// within the halves' log sigma times the family bound of M points (about
/// 5.9 for M = 25; a 9-seed sweep saw up to 3.9).
#[test]
fn the_photon_map_irradiance_on_the_floor_is_e_cos_theta() {
    let device = Device::new().unwrap();
    let prepared = Arc::new(sunlit_floor().commit(&device).unwrap());
    let out = trace(&prepared, Mode::Classic, 200_000, common::seed(31));
    let first: Vec<PhotonRecord> = out.records().into_iter().filter(|p| p.depth == 0).collect();
    let map = PhotonMap::build(&first);
    // Halves by a coin per photon, not by alternate records: the records'
    // order may follow space, and a random thinning of a Poisson process
    // gives two independent ones whatever the order.
    let mut coin = Rng::new(common::seed(32));
    let sides: Vec<bool> = first.iter().map(|_| coin.next_f32() < 0.5).collect();
    let half = |side: bool| {
        let h: Vec<PhotonRecord> = first
            .iter()
            .zip(&sides)
            .filter(|(_, &s)| s == side)
            .map(|(p, _)| PhotonRecord {
                power: p.power * 2.0,
                ..*p
            })
            .collect();
        PhotonMap::build(&h)
    };
    let halves = [half(false), half(true)];
    let k = 400;
    let lookup = |k| Lookup {
        k,
        max_radius: f32::INFINITY,
    };
    let expect = f64::from(E.x * cos_theta());
    let (mut ratios, mut diffs, mut logs) = (Vec::new(), Vec::new(), Vec::new());
    let mut scratch = Vec::new();
    for i in 0..5 {
        for j in 0..5 {
            let x = Vec3::new(-0.6 + 0.3 * i as f32, 0.0, -0.6 + 0.3 * j as f32);
            let est = irradiance_estimate(&map, x, Vec3::Y, lookup(k), &mut scratch);
            assert!(est.found == k && est.radius < 0.3, "{x}: {est:?}");
            let [e1, e2] = [0, 1].map(|h| {
                let e = irradiance_estimate(&halves[h], x, Vec3::Y, lookup(k / 2), &mut scratch);
                f64::from(e.value.x)
            });
            ratios.push(f64::from(est.value.x) / expect);
            diffs.push((e1 - e2) / (2.0 * expect));
            logs.push((e1 / e2).ln() / 2.0);
        }
    }
    let m = ratios.len() as f64;
    let pooled = |v: &[f64]| (v.iter().map(|d| d * d).sum::<f64>() / m).sqrt();
    let (s, s_log) = (pooled(&diffs), pooled(&logs));
    let mean = ratios.iter().sum::<f64>() / m;
    let worst = ratios
        .iter()
        .copied()
        .max_by(|a, b| a.ln().abs().total_cmp(&b.ln().abs()))
        .unwrap();
    eprintln!("mean ratio {mean:.4}, worst {worst:.4}, per-point sd {s:.4} ({s_log:.4} in logs)");
    common::assert_sigmas("mean ratio to E cos(theta)", mean - 1.0, s / m.sqrt(), 4.0);
    // The worst of M two-sided deviations, each against a sigma pooled from
    // M squares: Student's t with M degrees of freedom, Bonferroni over 2 M.
    let bound = common::family_bound(2 * ratios.len(), ratios.len() as u64, 1e-4);
    common::assert_sigmas("worst point's log ratio", worst.ln(), s_log, bound);
}

/// A delta light has no sampling noise: the renderer's light sample, the
/// path tracer's direct part and the quadrature give `E cos(theta)` (times
/// `albedo / pi` for radiance) to f32 rounding, and nothing below the floor.
#[test]
fn the_renderer_and_the_path_tracer_give_e_cos_theta_exactly() {
    let device = Device::new().unwrap();
    let scene = sunlit_floor();
    let eps = scene.ray_epsilon();
    let prepared = scene.commit(&device).unwrap();
    let lights = LightSampler::new(&prepared);
    let paths = PathTracer::new(&prepared);
    let brdf: Brdf = Lambert::new(Vec3::splat(ALBEDO)).unwrap().into();
    let irradiance = E * cos_theta();
    let radiance = irradiance * (ALBEDO / PI);
    let mut rng = Rng::new(5);
    for x in [
        Vec3::ZERO,
        Vec3::new(0.7, 0.0, -0.4),
        Vec3::new(-0.9, 0.0, 0.9),
    ] {
        let e = quadrature_irradiance(&prepared, x, Vec3::Y, 4);
        assert!(close(e, irradiance, 1e-5), "quadrature {e} at {x}");
        let u = rng.next_2d();
        let l = lights.sample(&brdf, [x, Vec3::Y, Vec3::Y, Vec3::Y], eps, u);
        assert!(close(l, radiance, 1e-5), "light sample {l} at {x}");
        let below = lights.sample(&brdf, [x, -Vec3::Y, -Vec3::Y, -Vec3::Y], eps, u);
        assert_eq!(below, Vec3::ZERO, "the floor's underside at {x}");
        let ray = Ray::new(x + Vec3::Y * 0.5, -Vec3::Y);
        let p = paths.radiance(ray, PathPart::Direct, false, &mut rng);
        assert!(close(p, radiance, 1e-5), "path tracer {p} at {x}");
    }
}

/// `tests/scenes/sun_floor.gltf`: the Sun node comes before the meshes, yet
/// its disc covers them all; the panel casts the Sun's shadow where the
/// file says; the floor gets photons from both lights; and the renderer's
/// light samples, picking between the two, average to the quadrature
/// within 4 of their own standard errors.
#[test]
fn a_sun_beside_an_emissive_panel_loads_and_lights_the_floor() {
    let scene = Scene::load(sun_floor_file()).unwrap();
    let kinds: Vec<&str> = scene.lights().iter().map(Light::kind).collect();
    assert_eq!(kinds, ["directional", "area"], "in the file's node order");
    let sun = sun_of(&scene);
    assert!((sun.direction() - sun_direction()).length() < 1e-6);
    assert!(close(sun.irradiance(), E, 1e-6));
    let r = (1.0f32 + 0.75 * 0.75 + 1.0).sqrt();
    assert!((sun.scene_radius() - r).abs() < 1e-6 * r);

    let device = Device::new().unwrap();
    let prepared = Arc::new(scene.clone().commit(&device).unwrap());
    let sunlit = E * cos_theta();
    // The panel's shadow: centred under it, moved 1.5 tan 30 towards -z.
    let shade = Vec3::new(0.0, 0.0, 0.3 - 1.5 * 30f32.to_radians().tan());
    let open = Vec3::new(0.6, 0.0, 0.6);
    let grid = 16;
    let full = |x| unshadowed_irradiance(&scene, x, Vec3::Y, grid);
    let seen = |x| quadrature_irradiance(&prepared, x, Vec3::Y, grid);
    assert!(close(seen(open), full(open), 1e-6));
    // Compared at the full value's scale: the difference loses f32 digits.
    assert!(
        close(seen(shade) + sunlit, full(shade), 1e-6),
        "{} + {sunlit} vs {}",
        seen(shade),
        full(shade)
    );
    assert!(full(open).x > sunlit.x, "both lights reach the open floor");

    let out = trace(&prepared, Mode::Classic, 50_000, 2);
    assert!(out.report.emitted_per_light.iter().all(|&n| n > 0));
    let (mut from_sun, mut from_panel) = (0, 0);
    for p in out.records().iter().filter(|p| p.depth == 0) {
        match p.direction.dot(sun.direction()).clamp(-1.0, 1.0).acos() <= MAX_DIRECTION_ERROR {
            true => from_sun += 1,
            false => from_panel += 1,
        }
    }
    // The panel has 3 % of the power, so about 3 % of the photons.
    assert!(
        from_sun > 10_000 && from_panel > 200,
        "{from_sun} / {from_panel}"
    );

    let lights = LightSampler::new(&prepared);
    let brdf: Brdf = Lambert::new(Vec3::splat(ALBEDO)).unwrap().into();
    let eps = scene.ray_epsilon();
    let mut rng = Rng::new(common::seed(41));
    let samples = common::MeanVar::of((0..20_000).map(|_| {
        let l = lights.sample(&brdf, [open, Vec3::Y, Vec3::Y, Vec3::Y], eps, rng.next_2d());
        f64::from(l.x)
    }));
    let want = f64::from(seen(open).x * ALBEDO / PI);
    common::assert_sigmas(
        "light samples against the quadrature",
        samples.mean() - want,
        samples.std_error(),
        4.0,
    );
}

#[test]
fn bad_directional_lights_are_refused_by_name() {
    let mut s = Scene::new();
    let refused = |s: &mut Scene, d: Vec3, e: Vec3| {
        let err = s
            .add_light(Light::Directional(DirectionalLight::new(d, e)))
            .unwrap_err();
        assert!(matches!(err, Error::InvalidScene(_)), "{err}");
        err.to_string()
    };
    for d in [
        Vec3::ZERO,
        Vec3::new(f32::NAN, 0.0, -1.0),
        Vec3::splat(f32::INFINITY),
    ] {
        let msg = refused(&mut s, d, E);
        assert!(msg.contains("directional light direction"), "{msg}");
    }
    for e in [
        Vec3::new(-1.0, 1.0, 1.0),
        Vec3::splat(f32::NAN),
        Vec3::splat(f32::INFINITY),
    ] {
        let msg = refused(&mut s, -Vec3::Y, e);
        assert!(msg.contains("directional light irradiance"), "{msg}");
    }
    assert!(s.lights().is_empty());

    // Alone, with nothing to light: no bounds, a clear error where it is checked.
    let sun = Light::Directional(DirectionalLight::new(-Vec3::Y, E));
    s.add_light(sun).unwrap();
    let msg = s.validate().unwrap_err().to_string();
    assert!(msg.contains("directional light but no triangle"), "{msg}");
    let device = Device::new().unwrap();
    let msg = s.commit(&device).unwrap_err().to_string();
    assert!(msg.contains("no bounds"), "{msg}");

    // Bright enough over the floor's disc to pass the power limit.
    let mut bright = sunlit_floor();
    let sun = Light::Directional(DirectionalLight::new(-Vec3::Y, Vec3::splat(1e30)));
    bright.add_light(sun).unwrap();
    let msg = bright.validate().unwrap_err().to_string();
    assert!(
        msg.contains("directional light 1") && msg.contains("above"),
        "{msg}"
    );
}

/// The file's Sun node edited by `edit`, loaded.
fn load_edited(edit: impl Fn(&mut serde_json::Value)) -> adaptive_pm::Result<Scene> {
    let text = std::fs::read_to_string(sun_floor_file()).unwrap();
    let mut doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    edit(&mut doc);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("edited.gltf");
    std::fs::write(&path, doc.to_string()).unwrap();
    Scene::load(&path)
}

#[test]
fn a_sun_without_direction_or_geometry_is_refused_on_load() {
    let flat = load_edited(|d| d["nodes"][0]["scale"] = serde_json::json!([0.0, 0.0, 0.0]));
    let msg = common::chain(&flat.unwrap_err());
    assert!(
        msg.contains("node 0 (`sun`)") && msg.contains("zero scale"),
        "{msg}"
    );
    let alone = load_edited(|d| d["scenes"][0]["nodes"] = serde_json::json!([0]));
    let msg = common::chain(&alone.unwrap_err());
    assert!(msg.contains("directional light but no triangle"), "{msg}");
}
