//! A partly transmitting surface (glTF's `0 < transmissionFactor < 1`):
//! `(1 - w) opaque + w glass`, a part picked per scattering event
//! (`Scene::set_transmission_mix`). Photons are stored on it whatever part
//! scatters them, and pass it by the glass part's share; the path tracer
//! and the photon renderer see through it by that share; and with a lit
//! opaque part, the photon render's image is the path tracer's. Each
//! statistical check derives its sigma from its own photons or pixels.

use adaptive_pm::brdf::dielectric::thin_slab_reflectance;
use adaptive_pm::brdf::{Brdf, Dielectric, Lambert};
use adaptive_pm::embree::{CommittedScene, Device};
use adaptive_pm::emitter::CosN;
use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
use adaptive_pm::render::{render, render_path, Image, PathHalves, PathPart, RenderConfig};
use adaptive_pm::sampling::luminance;
use adaptive_pm::scene::{Camera, Emission, Material, Scene};
use glam::Vec3;
use std::path::Path;

use super::caustic_pass::{material, quad};
use super::glass_transport::{black, slab_scene_of, R0, SLAB_HI, SLAB_LO};
use crate::common::{self, assert_sigmas, assert_within_noise, MeanVar};

const IOR: f32 = 1.5;
/// The glass part's share.
const WEIGHT: f32 = 0.3;

fn thin_glass() -> Brdf {
    Dielectric::new(IOR, Vec3::ONE, Vec3::ZERO, true)
        .unwrap()
        .into()
}

/// A horizontal sheet at `y`, its opaque part Lambert of albedo `albedo`,
/// letting the share [`WEIGHT`] through by thin glass.
fn mixed_sheet(s: &mut Scene, y: f32, half: f32, albedo: f32) {
    let opaque = material(
        s,
        "sheet",
        Lambert::new(Vec3::splat(albedo)).unwrap().into(),
    );
    s.set_transmission_mix(opaque, WEIGHT, thin_glass())
        .unwrap();
    quad(s, "sheet", y, half, true, opaque);
}

fn emitter(s: &mut Scene, radiance: f32, cosn: f32) -> usize {
    s.add_material(Material {
        name: "emitter".into(),
        brdf: Lambert::new(Vec3::ZERO).unwrap().into(),
        emission: Some(Emission::new(
            Vec3::splat(radiance),
            CosN::new(cosn).unwrap(),
        )),
    })
}

/// A black floor, the sheet (black opaque part) at y = 0.5, and a
/// near-collimated lamp (cos^n, n = 1e5) facing straight down onto it.
fn beam_scene() -> Scene {
    let mut s = Scene::new();
    let black = material(&mut s, "black", Lambert::new(Vec3::ZERO).unwrap().into());
    quad(&mut s, "floor", 0.0, 10.0, true, black);
    mixed_sheet(&mut s, 0.5, 10.0, 0.0);
    let lamp = emitter(&mut s, 1.0, 1e5);
    let pos = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .map(|(a, b)| Vec3::new(0.05 * a, 0.95, 0.05 * b))
        .to_vec();
    s.add_mesh("lamp", pos, vec![[0, 1, 2], [0, 2, 3]], lamp)
        .unwrap();
    s
}

/// The shares of the light's power stored on the sheet and on the floor,
/// and the emitted photon count.
fn stored_shares(
    tracer: &Tracer<CommittedScene>,
    scene: &Scene,
    mode: Mode,
    seed: u64,
) -> (f64, Vec<f64>) {
    let mut cfg = TraceConfig::new(mode, Budget::NMax(20_000));
    cfg.seed = common::seed(seed);
    let out = tracer.trace(&cfg).unwrap();
    let power = scene.lights()[0].power();
    let power = f64::from(power.x + power.y + power.z) / 3.0;
    let share = |r: &adaptive_pm::photon_map::PhotonRecord| {
        f64::from(r.power.x + r.power.y + r.power.z) / 3.0 / power
    };
    let records = out.records();
    let sheet: f64 = records
        .iter()
        .filter(|r| (r.position.y - 0.5).abs() < 1e-3)
        .map(share)
        .sum();
    let n: u64 = out.plans.iter().map(|p| p.photons).sum();
    // Per emitted photon (classic mode: at most one floor photon each).
    let mut floor: Vec<f64> = records
        .iter()
        .filter(|r| r.position.y < 1e-3)
        .map(|r| share(r) * n as f64)
        .collect();
    floor.resize(n as usize, 0.0);
    (sheet, floor)
}

#[test]
fn photons_are_stored_on_the_sheet_and_pass_it_by_the_glass_share() {
    let scene = beam_scene();
    let tracer = Tracer::new(scene.clone().commit(&Device::new().unwrap()).unwrap());
    // The thin sheet's transmittance at normal incidence, times the share.
    let through = f64::from(WEIGHT) * (1.0 - f64::from(thin_slab_reflectance(1.0, IOR)));
    // Every photon reaches the sheet first and is stored there with its
    // whole power, whatever part then scatters it: 1 up to the 16-byte
    // encoding's rounding, in either mode.
    let (sheet, floor) = stored_shares(&tracer, &scene, Mode::Classic, 31);
    assert!((sheet - 1.0).abs() < 1e-3, "classic: on the sheet {sheet}");
    let floor = MeanVar::of(floor);
    assert_sigmas(
        "classic: through the sheet",
        floor.mean() - through,
        floor.std_error(),
        4.0,
    );
    // Adaptive: split photons are correlated, so the sigma is the spread
    // of independent runs.
    let mut runs = MeanVar::default();
    for k in 0..8 {
        let (sheet, floor) = stored_shares(&tracer, &scene, Mode::Adaptive, 40 + k);
        assert!((sheet - 1.0).abs() < 1e-3, "adaptive: on the sheet {sheet}");
        runs.push(MeanVar::of(floor).mean());
    }
    let bound = common::family_bound(1, 7, 1e-4);
    assert_within_noise(
        "adaptive: through the sheet",
        runs.mean() - through,
        runs.std_error(),
        bound * runs.std_error(),
    );
}

/// The unit box's closed slab (y in [0.4, 0.6]) as a partly transmitting
/// volume: black opaque part, glass part of share [`WEIGHT`] absorbing
/// `sigma` per unit length. Straight down, a photon crosses the top face by
/// the glass part (`w (1 - R)`), is attenuated by `a = exp(-sigma d)`,
/// leaves by it (`w (1 - R)`), and may go round inside by two internal
/// glass reflections (`(w R a)^2` each time); the opaque part, black,
/// absorbs. To the floor: `w^2 (1 - R)^2 a / (1 - w^2 R^2 a^2)`. Stored on
/// the bottom face from inside, whatever part then scatters, attenuated:
/// `w (1 - R) a / (1 - w^2 R^2 a^2)`.
#[test]
fn a_partly_transmitting_volume_absorbs_whatever_part_scatters() {
    let sigma = 2.0f32;
    let slab = |s: &mut Scene| {
        let m = black(s);
        let glass = Dielectric::new(IOR, Vec3::ONE, Vec3::splat(sigma), false).unwrap();
        s.set_transmission_mix(m, WEIGHT, glass.into()).unwrap();
        m
    };
    let scene = slab_scene_of(slab, false, 0.0);
    let tracer = Tracer::new(scene.clone().commit(&Device::new().unwrap()).unwrap());
    let power = scene.lights()[0].power();
    let power = f64::from(power.x + power.y + power.z) / 3.0;
    let (w, a) = (
        f64::from(WEIGHT),
        (-f64::from(sigma) * f64::from(SLAB_HI - SLAB_LO)).exp(),
    );
    let round = 1.0 - (w * R0 * a).powi(2);
    let want_floor = (w * (1.0 - R0)).powi(2) * a / round;
    let want_inside = w * (1.0 - R0) * a / round;
    // The spread of independent runs: a photon may store more than once.
    let (mut floor, mut inside) = (MeanVar::default(), MeanVar::default());
    for k in 0..8 {
        let mut cfg = TraceConfig::new(Mode::Classic, Budget::NMax(40_000));
        cfg.seed = common::seed(80 + k);
        let out = tracer.trace(&cfg).unwrap();
        let share = |keep: &dyn Fn(&adaptive_pm::photon_map::PhotonRecord) -> bool| {
            let sum: f64 = out
                .records()
                .iter()
                .filter(|r| keep(r))
                .map(|r| f64::from(r.power.x + r.power.y + r.power.z) / 3.0)
                .sum();
            sum / power
        };
        floor.push(share(&|r| r.position.y < 1e-3));
        // On the bottom face, arriving downwards: from inside.
        inside.push(share(&|r| {
            (r.position.y - SLAB_LO).abs() < 1e-3 && r.direction.y < 0.0
        }));
    }
    let bound = common::family_bound(2, 7, 1e-4);
    for (check, runs, want) in [
        ("through the volume", &floor, want_floor),
        ("stored inside, attenuated", &inside, want_inside),
    ] {
        assert_within_noise(
            check,
            runs.mean() - want,
            runs.std_error(),
            bound * runs.std_error(),
        );
    }
    // Not the clear volume's: the attenuation is there.
    assert!(inside.mean() < 0.8 * w * (1.0 - R0));
}

/// An emitting floor (radiance 1, facing up) under the sheet (black
/// opaque part), seen from straight above through a narrow view.
fn window_scene() -> Scene {
    let mut s = Scene::new();
    let floor = emitter(&mut s, 1.0, 0.0);
    quad(&mut s, "floor", 0.0, 10.0, true, floor);
    mixed_sheet(&mut s, 0.5, 10.0, 0.0);
    let camera = Camera::look_at(Vec3::new(0.0, 3.0, 0.0), Vec3::ZERO, Vec3::Z, 10.0).unwrap();
    s.set_camera(camera).unwrap();
    s
}

fn mean_luminance(img: &Image) -> MeanVar {
    MeanVar::of(img.pixels.iter().map(|p| f64::from(luminance(*p))))
}

#[test]
fn the_renderers_see_the_light_behind_by_the_glass_share() {
    let scene = window_scene();
    let tracer = Tracer::new(scene.clone().commit(&Device::new().unwrap()).unwrap());
    let prepared = tracer.prepared();
    let mut cfg = RenderConfig::new(32, 32);
    cfg.spp = 64;
    cfg.seed = common::seed(41);
    // Within 5 degrees of the vertical, the thin sheet's transmittance
    // moves by under 1e-4: its value straight down stands for every pixel.
    let expected = f64::from(WEIGHT) * (1.0 - f64::from(thin_slab_reflectance(1.0, IOR)));
    let path = mean_luminance(&render_path(prepared, &cfg, PathPart::Full).unwrap());
    assert_sigmas(
        "path tracer through the sheet",
        path.mean() - expected,
        path.std_error().max(1e-4),
        4.0,
    );
    let mut tc = TraceConfig::new(Mode::Adaptive, Budget::NMax(20_000));
    tc.seed = cfg.seed;
    let out = tracer.trace(&tc).unwrap();
    let maps = cfg.build_maps(out.photons, out.frame);
    let photon = mean_luminance(&render(prepared, Some(&maps), &cfg).unwrap());
    assert_sigmas(
        "photon render through the sheet",
        photon.mean() - expected,
        photon.std_error().max(1e-4),
        4.0,
    );
}

/// A grey floor, the sheet (grey opaque part) over its middle, and a
/// small lamp above, seen from the side: the opaque part lit from above
/// and through the glass part from below, the floor lit through it.
fn lit_sheet_scene() -> Scene {
    let mut s = Scene::new();
    let grey = material(
        &mut s,
        "grey",
        Lambert::new(Vec3::splat(0.5)).unwrap().into(),
    );
    quad(&mut s, "floor", 0.0, 2.0, true, grey);
    mixed_sheet(&mut s, 0.5, 0.6, 0.6);
    let lamp = emitter(&mut s, 30.0, 0.0);
    let pos = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .map(|(a, b)| Vec3::new(0.3 + 0.15 * a, 1.6, 0.15 * b))
        .to_vec();
    s.add_mesh("lamp", pos, vec![[0, 1, 2], [0, 2, 3]], lamp)
        .unwrap();
    let camera = Camera::look_at(Vec3::new(0.0, 2.2, 2.6), Vec3::ZERO, Vec3::Y, 45.0).unwrap();
    s.set_camera(camera).unwrap();
    s
}

/// The photon render's image (four independent renders, 16 spp) sums to
/// the path tracer's (two halves of 1024 spp) within their measured noise.
fn assert_renders_agree(check: &str, scene: &Scene, size: (u32, u32), seed: u64) {
    assert_renders_agree_with(check, scene, RenderConfig::new(size.0, size.1), seed);
}

/// [`assert_renders_agree`] with the photon renders' settings `cfg` (its
/// size, its cache).
pub(crate) fn assert_renders_agree_with(
    check: &str,
    scene: &Scene,
    mut cfg: RenderConfig,
    seed: u64,
) {
    let tracer = Tracer::new(scene.clone().commit(&Device::new().unwrap()).unwrap());
    let prepared = tracer.prepared();
    let (width, height) = (cfg.width, cfg.height);
    cfg.show_emitters = false;
    let pixels = f64::from(width * height);

    let mut pc = cfg.clone();
    pc.spp = 1024;
    pc.seed = common::seed(seed);
    let halves = PathHalves::render(prepared, &pc, PathPart::Full).unwrap();
    let sum = |img: &Image| -> f64 { img.pixels.iter().map(|p| f64::from(luminance(*p))).sum() };
    let path = sum(&halves.mean());
    // Var of the mean of two halves: (a - b)^2 / 4 per pixel.
    let path_var: f64 = halves
        .a
        .pixels
        .iter()
        .zip(&halves.b.pixels)
        .map(|(a, b)| (f64::from(luminance(*a)) - f64::from(luminance(*b))).powi(2) / 4.0)
        .sum();

    let mut photon = MeanVar::default();
    for k in 0..4 {
        let mut tc = TraceConfig::new(Mode::Adaptive, Budget::NMax(100_000));
        tc.seed = common::seed(seed + 1 + k);
        let out = tracer.trace(&tc).unwrap();
        let maps = cfg.build_maps(out.photons, out.frame);
        let mut rc = cfg.clone();
        rc.spp = 16;
        rc.seed = tc.seed;
        photon.push(sum(&render(prepared, Some(&maps), &rc).unwrap()));
    }
    let v_photon = photon.std_error().powi(2);
    let sigma = (path_var + v_photon).sqrt();
    eprintln!(
        "{check}: photon {:.3} (+- {:.3}), path {path:.3} (+- {:.3})",
        photon.mean(),
        photon.std_error(),
        path_var.sqrt()
    );
    // Student's t at the Welch–Satterthwaite degrees of freedom: about one
    // per pixel for the path tracer's variance, three for the photon
    // renders' spread.
    let dof = (path_var + v_photon).powi(2) / (path_var.powi(2) / pixels + v_photon.powi(2) / 3.0);
    let bound = common::family_bound(1, dof as u64, 1e-4);
    assert_within_noise(check, photon.mean() - path, sigma, bound * sigma);
}

#[test]
fn a_lit_partly_transmitting_sheet_renders_as_the_path_tracer_sees_it() {
    assert_renders_agree("the lit sheet's image", &lit_sheet_scene(), (32, 32), 51);
}

/// `assets/blender_frosted.glb`, written by Blender 3.4's exporter
/// (`tools/blender_frosted.py`): a pane of Principled Transmission 0.5,
/// roughness 0.3, over a floor, under an emitting panel.
#[test]
fn blenders_frosted_pane_is_half_glass_and_renders_as_the_path_tracer_sees_it() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/blender_frosted.glb");
    let scene = Scene::load(file).unwrap();
    let pane = scene
        .meshes()
        .iter()
        .find(|m| m.name.starts_with("pane"))
        .unwrap();
    let Brdf::GltfPbr(opaque) = scene.materials()[pane.material].brdf else {
        panic!("the pane's opaque part is glTF's BRDF")
    };
    assert_eq!(opaque.f0(), Vec3::splat(0.04));
    let mix = scene.transmission_mix(pane.material as u32).unwrap();
    assert_eq!(mix.weight, 0.5);
    let Brdf::RoughDielectric(glass) = scene.materials()[mix.glass].brdf else {
        panic!("roughness 0.3: rough glass")
    };
    assert_eq!((glass.ior(), glass.thin()), (1.5, true));
    assert!((glass.alpha() - 0.09).abs() < 1e-6, "{}", glass.alpha());
    assert_renders_agree("Blender's frosted pane", &scene, (32, 24), 71);
}
