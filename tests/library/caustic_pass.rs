//! The caustic pass (`Tracer::trace_caustic`): photons aimed at the
//! specular objects give the main trace's caustic power, region by region,
//! for every kind of light (the sampler is in `caustic_aim.rs`, runs on
//! `cornell-glass` in `caustic_runs.rs`). Each statistical check measures
//! its own sigma from the photons it compares.

use adaptive_pm::brdf::{Dielectric, Lambert, Mirror};
use adaptive_pm::embree::Device;
use adaptive_pm::emitter::CosN;
use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
use adaptive_pm::photon_map::PhotonRecord;
use adaptive_pm::sampling::luminance;
use adaptive_pm::scene::{
    DirectionalLight, Emission, Light, Material, PointLight, Scene, SpotLight,
};
use glam::Vec3;
use std::collections::BTreeMap;
use std::f32::consts::PI;

use crate::common::{self, assert_within_noise};

const MIRROR_CENTRE: Vec3 = Vec3::new(-0.6, 0.5, 0.0);
const GLASS_CENTRE: Vec3 = Vec3::new(0.6, 0.5, 0.0);
const RADIUS: f32 = 0.4;

pub(crate) fn material(s: &mut Scene, name: &str, brdf: adaptive_pm::brdf::Brdf) -> usize {
    s.add_material(Material {
        name: name.into(),
        brdf,
        emission: None,
    })
}

/// A UV sphere of outward-wound triangles.
pub(crate) fn sphere(s: &mut Scene, name: &str, centre: Vec3, r: f32, mat: usize) {
    let (stacks, slices) = (24u32, 48u32);
    let mut pos = Vec::new();
    for i in 0..=stacks {
        let theta = PI * i as f32 / stacks as f32;
        for j in 0..slices {
            let phi = 2.0 * PI * j as f32 / slices as f32;
            let d = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            pos.push(centre + d * r);
        }
    }
    let at = |i: u32, j: u32| i * slices + j % slices;
    let mut idx = Vec::new();
    for i in 0..stacks {
        for j in 0..slices {
            for t in [
                [at(i, j), at(i + 1, j), at(i + 1, j + 1)],
                [at(i, j), at(i + 1, j + 1), at(i, j + 1)],
            ] {
                let [a, b, c] = t.map(|k| pos[k as usize]);
                let outward = (b - a).cross(c - a).dot(a + b + c - 3.0 * centre) > 0.0;
                idx.push(if outward { t } else { [t[0], t[2], t[1]] });
            }
        }
    }
    s.add_mesh(name, pos, idx, mat).unwrap();
}

pub(crate) fn quad(s: &mut Scene, name: &str, y: f32, half: f32, up: bool, mat: usize) {
    let pos = vec![
        Vec3::new(-half, y, -half),
        Vec3::new(half, y, -half),
        Vec3::new(half, y, half),
        Vec3::new(-half, y, half),
    ];
    // (b - a) x (c - a) is -y for this order.
    let idx = if up {
        vec![[0, 2, 1], [0, 3, 2]]
    } else {
        vec![[0, 1, 2], [0, 2, 3]]
    };
    s.add_mesh(name, pos, idx, mat).unwrap();
}

/// A black floor (y = 0), a mirror sphere and a tinted, absorbing glass
/// sphere on it, and the light `light` adds.
fn spheres_over_black(light: impl FnOnce(&mut Scene)) -> Scene {
    let mut s = Scene::new();
    let black = material(&mut s, "black", Lambert::new(Vec3::ZERO).unwrap().into());
    let mirror = material(
        &mut s,
        "mirror",
        Mirror::new(Vec3::splat(0.9)).unwrap().into(),
    );
    let glass = Dielectric::new(1.5, Vec3::ONE, Vec3::new(0.2, 0.5, 1.0), false).unwrap();
    let glass = material(&mut s, "glass", glass.into());
    quad(&mut s, "floor", 0.0, 2.0, true, black);
    sphere(&mut s, "mirror", MIRROR_CENTRE, RADIUS, mirror);
    sphere(&mut s, "glass", GLASS_CENTRE, RADIUS, glass);
    light(&mut s);
    s.validate().unwrap();
    s
}

fn area_light(cosn: f32, two_sided: bool) -> impl FnOnce(&mut Scene) {
    move |s| {
        let mut e = Emission::new(Vec3::new(4.0, 3.0, 2.0), CosN::new(cosn).unwrap());
        e.two_sided = two_sided;
        let m = s.add_material(Material {
            name: "lamp".into(),
            brdf: Lambert::new(Vec3::ZERO).unwrap().into(),
            emission: Some(e),
        });
        quad(s, "lamp", 2.5, 0.4, false, m);
    }
}

fn punctual(light: Light) -> impl FnOnce(&mut Scene) {
    move |s| {
        s.add_light(light).unwrap();
    }
}

/// Caustic power per floor cell (luminance): its sum and its variance as
/// a sum over `emitted` independent photons that each store at most one
/// caustic photon (`sum x^2 - S^2 / N`).
fn cells(records: &[PhotonRecord], emitted: u64) -> BTreeMap<(i32, i32), (f64, f64, u64)> {
    let mut m: BTreeMap<(i32, i32), (f64, f64, u64)> = BTreeMap::new();
    for r in records.iter().filter(|r| r.caustic && r.position.y < 1e-3) {
        let key = (
            (r.position.x / 0.25).floor() as i32,
            (r.position.z / 0.25).floor() as i32,
        );
        let x = luminance(r.power) as f64;
        let e = m.entry(key).or_default();
        e.0 += x;
        e.1 += x * x;
        e.2 += 1;
    }
    for v in m.values_mut() {
        v.1 = (v.1 - v.0 * v.0 / emitted as f64).max(0.0);
    }
    m
}

/// The main trace's caustic photons (classic: independent photons, at most
/// one caustic store each) against the pass's, cell by cell and in all.
fn assert_pass_matches_main(name: &str, scene: Scene, main_n: u64, pass_n: u64) {
    let device = Device::new().unwrap();
    let tracer = Tracer::new(scene.commit(&device).unwrap());
    let mut cfg = TraceConfig::new(Mode::Classic, Budget::NMax(main_n));
    cfg.seed = common::seed(41);
    let main = tracer.trace(&cfg).unwrap();
    let main_emitted: u64 = main.plans.iter().map(|p| p.photons).sum();
    cfg.seed = common::seed(42);
    let pass = tracer.trace_caustic(&cfg, pass_n).unwrap();
    assert_eq!(pass.report.emitted, pass_n, "{name}");
    let a = cells(&main.records(), main_emitted);
    let b = cells(&pass.records(), pass.report.emitted);
    let compared: Vec<_> = a.iter().filter(|(_, v)| v.2 >= 200).collect();
    assert!(
        compared.len() >= 3,
        "{name}: {} cells with caustic photons",
        compared.len()
    );
    let bound = common::family_bound(compared.len() + 1, 1000, 1e-4);
    let (mut sa, mut sb, mut va, mut vb) = (0.0, 0.0, 0.0, 0.0);
    for (key, &(s_main, v_main, _)) in &a {
        let (s_pass, v_pass, _) = b.get(key).copied().unwrap_or_default();
        (sa, sb, va, vb) = (sa + s_main, sb + s_pass, va + v_main, vb + v_pass);
        if compared.iter().any(|(k, _)| *k == key) {
            let sigma = (v_main + v_pass).sqrt();
            let check = format!("{name} cell {key:?}");
            assert_within_noise(&check, s_pass - s_main, sigma, bound * sigma);
        }
    }
    // Cells the main trace never reached hold next to nothing of the pass's.
    for (key, &(s_pass, v_pass, _)) in b.iter().filter(|(k, _)| !a.contains_key(k)) {
        (sb, vb) = (sb + s_pass, vb + v_pass);
        let _ = key;
    }
    let sigma = (va + vb).sqrt();
    assert_within_noise(&format!("{name} total"), sb - sa, sigma, bound * sigma);
    // The pass aims: more of its photons are caustic photons (a spot's
    // cone already holds the spheres: only twice as many there).
    let share_main =
        main.records().iter().filter(|r| r.caustic).count() as f64 / main_emitted as f64;
    let share_pass = pass.report.stored as f64 / pass_n as f64;
    assert!(
        share_pass > 2.0 * share_main,
        "{name}: {share_pass} vs {share_main}"
    );
}

#[test]
fn the_pass_gives_the_main_traces_caustic_power_under_an_area_light() {
    assert_pass_matches_main(
        "cosn 4",
        spheres_over_black(area_light(4.0, false)),
        3_000_000,
        300_000,
    );
}

#[test]
fn the_pass_gives_the_main_traces_caustic_power_under_a_two_sided_light() {
    assert_pass_matches_main(
        "two-sided",
        spheres_over_black(area_light(0.0, true)),
        3_000_000,
        300_000,
    );
}

#[test]
fn the_pass_gives_the_main_traces_caustic_power_under_punctual_lights() {
    let point = Light::Point(PointLight {
        position: Vec3::new(0.1, 2.5, 0.2),
        intensity: Vec3::new(1.0, 2.0, 3.0),
    });
    assert_pass_matches_main(
        "point",
        spheres_over_black(punctual(point)),
        3_000_000,
        300_000,
    );
    let spot = Light::Spot(SpotLight {
        position: Vec3::new(0.0, 2.5, 0.0),
        direction: -Vec3::Y,
        intensity: Vec3::splat(5.0),
        cos_inner: 12f32.to_radians().cos(),
        cos_outer: 25f32.to_radians().cos(),
    });
    assert_pass_matches_main(
        "spot",
        spheres_over_black(punctual(spot)),
        2_000_000,
        300_000,
    );
    let sun = DirectionalLight::new(Vec3::new(0.3, -1.0, 0.2), Vec3::splat(2.0));
    let sun = Light::Directional(sun);
    assert_pass_matches_main("sun", spheres_over_black(punctual(sun)), 3_000_000, 300_000);
}
