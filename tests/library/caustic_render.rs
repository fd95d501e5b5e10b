//! The rendered caustic with a caustic pass against the path tracer: a
//! glass ball lit from the side by a small lamp focuses it on a grey
//! floor, seen from above. Over the floor's pixels around the caustic, the
//! photon render's indirect light (its full view minus its direct-only
//! view: the pass's caustic map plus the gather) sums to the path
//! tracer's indirect part (`PathPart::Indirect`: the caustic and the light
//! the floor sends back through the ball). The sigma is measured: per
//! pixel from the path tracer's two halves, and from four independent
//! photon renders.

use adaptive_pm::brdf::{Dielectric, Lambert};
use adaptive_pm::embree::Device;
use adaptive_pm::emitter::CosN;
use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
use adaptive_pm::render::{
    render, render_path, specular_pixels, Image, PathHalves, PathPart, RenderConfig, View,
};
use adaptive_pm::sampling::luminance;
use adaptive_pm::scene::{Camera, Emission, Material, Scene};
use glam::Vec3;

use super::caustic_pass::{material, quad, sphere};
use crate::common::{self, assert_within_noise, MeanVar};

const BALL: Vec3 = Vec3::new(0.0, 0.7, 0.0);
/// Where the light's ray through the ball's centre meets the floor.
const SPOT: Vec3 = Vec3::new(-0.7, 0.0, 0.0);

fn ball_over_grey() -> Scene {
    let mut s = Scene::new();
    let grey = material(
        &mut s,
        "grey",
        Lambert::new(Vec3::splat(0.5)).unwrap().into(),
    );
    let glass = Dielectric::new(1.5, Vec3::ONE, Vec3::ZERO, false).unwrap();
    let glass = material(&mut s, "glass", glass.into());
    quad(&mut s, "floor", 0.0, 2.0, true, grey);
    sphere(&mut s, "ball", BALL, 0.3, glass);
    // A small lamp facing down, off to the side (a point light's caustic
    // is beyond a path tracer without shadow rays through glass).
    let lamp = s.add_material(Material {
        name: "lamp".into(),
        brdf: Lambert::new(Vec3::ZERO).unwrap().into(),
        emission: Some(Emission::new(Vec3::splat(40.0), CosN::new(0.0).unwrap())),
    });
    let pos = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .map(|(a, b)| Vec3::new(2.0 + 0.15 * a, 2.7, 0.15 * b))
        .to_vec();
    s.add_mesh("lamp", pos, vec![[0, 1, 2], [0, 2, 3]], lamp)
        .unwrap();
    let camera = Camera::look_at(Vec3::new(-1.2, 5.0, 0.0), SPOT, Vec3::Z, 40.0).unwrap();
    s.set_camera(camera).unwrap();
    s.validate().unwrap();
    s
}

/// The floor's pixels (first hit not specular) within 0.6 of the spot.
fn region(
    scene: &Scene,
    prepared: &adaptive_pm::embree::EmbreeScene,
    cfg: &RenderConfig,
) -> Vec<bool> {
    let specular = specular_pixels(prepared, cfg).unwrap();
    let cam = scene.camera().unwrap();
    let (w, h) = (cfg.width as usize, cfg.height as usize);
    let right = cam.forward.cross(cam.up).normalize();
    let tan = (cam.vfov_deg.to_radians() * 0.5).tan();
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            let sx = (2.0 * x / w as f32 - 1.0) * tan * w as f32 / h as f32;
            let sy = (1.0 - 2.0 * y / h as f32) * tan;
            let d = (cam.forward + right * sx + cam.up * sy).normalize();
            let t = -cam.eye.y / d.y;
            let floor = cam.eye + d * t;
            !specular[i] && (floor - SPOT).length() < 0.6
        })
        .collect()
}

fn masked_sum(img: &Image, mask: &[bool]) -> f64 {
    img.pixels
        .iter()
        .zip(mask)
        .filter(|(_, &m)| m)
        .map(|(p, _)| luminance(*p) as f64)
        .sum()
}

#[test]
fn the_passes_rendered_caustic_matches_the_path_tracer() {
    let scene = ball_over_grey();
    let tracer = Tracer::new(scene.clone().commit(&Device::new().unwrap()).unwrap());
    let prepared = tracer.prepared();
    let mut cfg = RenderConfig::new(64, 64);
    cfg.show_emitters = false;
    let mask = region(&scene, prepared, &cfg);
    let pixels = mask.iter().filter(|&&m| m).count();
    assert!(pixels > 300, "{pixels} pixels in the region");

    let mut pc = cfg.clone();
    pc.spp = 4096;
    pc.seed = common::seed(11);
    let halves = PathHalves::render(prepared, &pc, PathPart::Indirect).unwrap();
    let path = masked_sum(&halves.mean(), &mask);
    // The region holds the caustic: most of its indirect light is the caustic part.
    let caustic = masked_sum(
        &render_path(prepared, &pc, PathPart::Caustic).unwrap(),
        &mask,
    );
    assert!(caustic > 0.5 * path, "caustic {caustic} of indirect {path}");
    // Var of the mean of two halves: (a - b)^2 / 4 per pixel.
    let path_var: f64 = halves
        .a
        .pixels
        .iter()
        .zip(&halves.b.pixels)
        .zip(&mask)
        .filter(|(_, &m)| m)
        .map(|((a, b), _)| (luminance(*a) as f64 - luminance(*b) as f64).powi(2) / 4.0)
        .sum();

    let mut photon = MeanVar::default();
    for k in 0..4 {
        let mut tc = TraceConfig::new(Mode::Adaptive, Budget::NMax(100_000));
        tc.seed = common::seed(20 + k);
        let main = tracer.trace(&tc).unwrap();
        let pass = tracer.trace_caustic(&tc, 400_000).unwrap();
        assert!(pass.report.stored > 50_000, "{:?}", pass.report);
        let maps = cfg
            .build_maps(main.photons, main.frame)
            .with_caustic_pass(pass);
        let mut rc = cfg.clone();
        rc.spp = 16;
        rc.seed = tc.seed;
        let full = render(prepared, Some(&maps), &rc).unwrap();
        rc.view = View::DirectOnly;
        let direct = render(prepared, Some(&maps), &rc).unwrap();
        photon.push(masked_sum(&full, &mask) - masked_sum(&direct, &mask));
    }
    let sigma = (path_var + photon.std_error().powi(2)).sqrt();
    eprintln!(
        "caustic region: photon {:.4} (+- {:.4}), path {path:.4} (+- {:.4})",
        photon.mean(),
        photon.std_error(),
        path_var.sqrt()
    );
    // Student's t at the Welch–Satterthwaite degrees of freedom: about
    // one per pixel for the path tracer's variance, three for the photon
    // renders' spread.
    let v_photon = photon.std_error().powi(2);
    let dof =
        (path_var + v_photon).powi(2) / (path_var.powi(2) / pixels as f64 + v_photon.powi(2) / 3.0);
    let bound = common::family_bound(1, dof as u64, 1e-4);
    assert_within_noise(
        "indirect over the caustic",
        photon.mean() - path,
        sigma,
        bound * sigma,
    );
}
