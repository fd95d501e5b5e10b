//! A small renderer built on adaptive-pm the way a renderer author would use
//! it: the library with default features off and the three a renderer uses
//! (`features = ["embree", "gltf", "image-io"]`), a scene built in code, a
//! tracer stored in the renderer's own struct and shared by two threads, a
//! run and a render through the renderer's own ray caster, an image written,
//! and a glTF file loaded.
//!
//! It checks what it relies on and exits non-zero otherwise:
//! 1. two threads tracing through one stored tracer get the same photon map;
//! 2. the map's first-hit power is the light's power (a closed box);
//! 3. its own caster and Embree give the same emission and, within the
//!    noise of float rounding at triangle edges, the same map;
//! 4. rendered from the same map, its own caster's image is Embree's within
//!    that rounding, and it writes as OpenEXR;
//! 5. a glTF file exported by Blender loads, traces and stores photons.

mod caster;

use adaptive_pm::embree::{thread_pool, Device};
use adaptive_pm::engine::{Budget, Mode, TraceConfig, TraceOutput, Tracer};
use adaptive_pm::photon_map::{Neighbor, PhotonMap};
use adaptive_pm::raycast::RayCaster;
use adaptive_pm::render::{render, Image, RenderConfig, RenderMaps};
use adaptive_pm::scene::{Camera, Emission, Material, PreparedScene, Scene};
use adaptive_pm::{brdf, emitter::CosN};
use glam::Vec3;
use std::f32::consts::PI;

/// Half-size of the box, and the light's half-size and radiance.
const HALF: f32 = 1.0;
const LIGHT_HALF: f32 = 0.25;
const RADIANCE: f32 = 10.0;

/// A closed grey box with a square light under its ceiling, facing down.
fn build_scene() -> adaptive_pm::Result<Scene> {
    let mut scene = Scene::new();
    let grey = scene.add_material(Material {
        name: "grey".into(),
        brdf: brdf::Brdf::Lambert(brdf::Lambert {
            albedo: Vec3::splat(0.5),
        }),
        emission: None,
    });
    let light = scene.add_material(Material {
        name: "light".into(),
        brdf: brdf::Brdf::Lambert(brdf::Lambert { albedo: Vec3::ZERO }),
        emission: Some(Emission::new(Vec3::splat(RADIANCE), CosN::new(0.0)?)),
    });
    // Eight corners of the box; each face wound to face inwards.
    let h = HALF;
    let corners: Vec<Vec3> = (0..8)
        .map(|i| {
            Vec3::new(
                if i & 1 == 0 { -h } else { h },
                if i & 2 == 0 { -h } else { h },
                if i & 4 == 0 { -h } else { h },
            )
        })
        .collect();
    let faces: [[u32; 4]; 6] = [
        [0, 1, 3, 2],
        [4, 6, 7, 5],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 5, 7, 3],
    ];
    for (i, [a, b, c, d]) in faces.into_iter().enumerate() {
        scene.add_mesh(
            format!("wall{i}"),
            corners.clone(),
            vec![[a, b, c], [a, c, d]],
            grey,
        )?;
    }
    let (l, y) = (LIGHT_HALF, HALF * 0.99);
    let quad = vec![
        Vec3::new(-l, y, -l),
        Vec3::new(l, y, -l),
        Vec3::new(l, y, l),
        Vec3::new(-l, y, l),
    ];
    // Counter-clockwise seen from below: the normal points down (-y).
    scene.add_mesh("light", quad, vec![[0, 1, 2], [0, 2, 3]], light)?;
    Ok(scene)
}

/// The renderer: it owns its tracer (no borrow of the scene).
struct Renderer<C> {
    tracer: Tracer<C>,
    config: TraceConfig,
}

impl<C: RayCaster> Renderer<C> {
    fn new(prepared: PreparedScene<C>) -> Self {
        let mut config = TraceConfig::new(Mode::Adaptive, Budget::NMax(20_000));
        config.seed = 7;
        Renderer {
            tracer: Tracer::new(prepared),
            config,
        }
    }

    fn trace(&self) -> adaptive_pm::Result<TraceOutput> {
        self.tracer.trace(&self.config)
    }
}

/// Irradiance on the floor's centre from the map (k nearest photons facing up).
fn floor_irradiance(map: &PhotonMap) -> f32 {
    let mut near: Vec<Neighbor> = Vec::new();
    let x = Vec3::new(0.0, -HALF, 0.0);
    map.nearest_k_facing(x, Vec3::Y, 400, f32::INFINITY, &mut near);
    let r2 = near.last().map_or(1.0, |n| n.dist2);
    let power: f32 = near
        .iter()
        .map(|n| map.photon(n.index).power.element_sum() / 3.0)
        .sum();
    power / (PI * r2)
}

fn check(ok: bool, what: &str) -> Result<(), String> {
    println!("{} {what}", if ok { "ok  " } else { "FAIL" });
    ok.then_some(()).ok_or_else(|| what.to_string())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let scene = build_scene()?;
    let device = Device::new()?;
    let pool = thread_pool(2)?;

    // Embree, one stored tracer, two threads.
    let embree = Renderer::new(scene.clone().commit(&device)?);
    let (a, b) = pool.install(|| {
        std::thread::scope(|s| {
            let ta = s.spawn(|| embree.trace());
            let tb = s.spawn(|| embree.trace());
            (ta.join().expect("thread a"), tb.join().expect("thread b"))
        })
    });
    let (a, b) = (a?, b?);
    let emitted = a.report.emitted;
    let depth0_power = a.report.depths[0].stored_power_luminance;
    let maps = RenderMaps::build(&a.records());
    let (map_a, map_b) = (a.into_map(), b.into_map());
    println!(
        "embree: {emitted} photons emitted, {} stored, checksum {:016x}",
        map_a.len(),
        map_a.checksum()
    );
    check(
        map_a.checksum() == map_b.checksum(),
        "two threads, one tracer: the same photon map",
    )?;

    // A diffuse square light of side 2l and radiance L emits L * area * pi,
    // and in a closed box every photon's first hit stores it.
    let light_power = RADIANCE * (2.0 * LIGHT_HALF).powi(2) * PI;
    let rel = (depth0_power as f32 - light_power).abs() / light_power;
    println!("first-hit power {depth0_power:.4} W, light power {light_power:.4} W");
    check(rel < 1e-3, "first-hit power is the light's power")?;

    // The renderer's own caster on the same scene.
    let own = Renderer::new(PreparedScene::new(
        scene.clone(),
        caster::BruteForce::new(&scene),
    )?);
    let c = pool.install(|| own.trace())?;
    check(
        c.report.emitted == emitted,
        "own caster: the same photons emitted",
    )?;
    let map_c = c.into_map();
    println!(
        "own caster: {} stored, checksum {:016x}",
        map_c.len(),
        map_c.checksum()
    );
    let stored_rel = (map_c.len() as f64 - map_a.len() as f64).abs() / map_a.len() as f64;
    check(
        stored_rel < 0.01,
        "own caster: stored count within 1 % of Embree's",
    )?;
    let (ea, ec) = (floor_irradiance(&map_a), floor_irradiance(&map_c));
    println!("floor irradiance: embree {ea:.4}, own caster {ec:.4} W/m^2");
    check(
        (ea - ec).abs() / ea < 0.02,
        "own caster: floor irradiance within 2 % of Embree's",
    )?;
    if map_c.checksum() == map_a.checksum() {
        println!("own caster and Embree: identical photon maps");
    }

    // Rendering: one map, both casters. Only the casters' hits differ.
    let mut rc = RenderConfig::new(48, 48);
    rc.spp = 4;
    rc.camera = Some(Camera::look_at(
        Vec3::new(0.0, 0.0, 0.95 * HALF),
        Vec3::new(0.0, 0.0, -HALF),
        Vec3::Y,
        75.0,
    )?);
    let image_embree = pool.install(|| render(embree.tracer.prepared(), Some(&maps), &rc))?;
    let image_own = pool.install(|| render(own.tracer.prepared(), Some(&maps), &rc))?;
    let (me, mo) = (image_embree.mean(), image_own.mean());
    println!("image mean: embree {:.4}, own caster {:.4}", me.x, mo.x);
    check(
        (me - mo).abs().max_element() <= 1e-3 * me.max_element() && me.max_element() > 0.0,
        "own caster: the image of the same map is Embree's within 0.1 %",
    )?;
    let out =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/downstream-box.exr");
    image_own.write_exr(&out)?;
    let back = Image::read_exr(&out)?;
    check(
        back.pixels == image_own.pixels,
        "the image written as OpenEXR reads back",
    )?;
    println!("wrote {}", out.display());

    // A glTF scene (Blender's export, in the repository's assets).
    let glb =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/blender_scene.glb");
    let loaded = Renderer::new(Scene::load(&glb)?.commit(&device)?);
    let run = pool.install(|| loaded.trace())?;
    println!("{}: {} photons stored", glb.display(), run.photons.len());
    check(
        !run.photons.is_empty(),
        "a glTF file loads, traces and stores photons",
    )?;
    Ok(())
}
