//! The built-in `door` (Veach's two rooms, issue 27; `tools/make_door.py`):
//! closed diffuse boxes, a camera that sees no light, light in the camera's
//! room only through the doorway, light that does reach it, and stored
//! flux that the light's power and the albedos bound.

use adaptive_pm::brdf::Brdf;
use adaptive_pm::embree::{Device, Ray};
use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
use adaptive_pm::render::{render, render_path, CameraRays, PathPart, RenderConfig, RenderMaps};
use adaptive_pm::rng::Rng;
use adaptive_pm::sampling::uniform_hemisphere;
use adaptive_pm::scene::{builtin_names, Light, Scene, BUILTIN_DOOR};
use glam::Vec3;
use std::sync::Arc;

/// The partition between the rooms, x in [400, 415] (tools/make_door.py).
const WALL_X: (f32, f32) = (400.0, 415.0);
/// The doorway in it: z in [150, 240], up to y = 210.
const DOORWAY_Z: (f32, f32) = (150.0, 240.0);
const DOORWAY_TOP: f32 = 210.0;

fn door() -> Scene {
    Scene::open(BUILTIN_DOOR).unwrap()
}

/// The light panel's corners' bounding box.
fn light_box(scene: &Scene) -> (Vec3, Vec3) {
    let light = scene
        .meshes()
        .iter()
        .find(|m| scene.materials()[m.material].emission.is_some())
        .unwrap();
    let lo = light
        .positions
        .iter()
        .fold(Vec3::INFINITY, |a, &p| a.min(p));
    let hi = light
        .positions
        .iter()
        .fold(Vec3::NEG_INFINITY, |a, &p| a.max(p));
    (lo, hi)
}

fn random_direction(rng: &mut Rng) -> Vec3 {
    let d = uniform_hemisphere(rng.next_2d());
    if rng.next_f32() < 0.5 {
        d
    } else {
        -d
    }
}

#[test]
fn door_is_a_built_in_of_closed_diffuse_boxes() {
    assert!(builtin_names().contains(&BUILTIN_DOOR));
    let scene = door();
    assert_eq!(scene.lights().len(), 1);
    assert!(matches!(scene.lights()[0], Light::Area(_)));
    for m in scene.meshes() {
        let material = &scene.materials()[m.material];
        assert!(
            matches!(material.brdf, Brdf::Lambert(_)),
            "{}: {:?}",
            m.name,
            material.brdf
        );
        if material.emission.is_none() {
            assert_eq!(m.indices.len(), 12, "{}: a box has 12 triangles", m.name);
        }
    }
    // Closed: rays from anywhere inside either room, any direction, all hit.
    let device = Device::new().unwrap();
    let rt = scene.embree_geometry(&device).unwrap();
    let mut rng = Rng::new(crate::common::seed(27));
    let rooms = [(5.0, 395.0), (440.0, 810.0)];
    for i in 0..20_000 {
        let (x0, x1) = rooms[i % 2];
        let [u, v] = rng.next_2d();
        let o = Vec3::new(
            x0 + u * (x1 - x0),
            5.0 + 250.0 * v,
            5.0 + 390.0 * rng.next_f32(),
        );
        let d = random_direction(&mut rng);
        assert!(
            rt.intersect(&Ray::new(o, d)).is_some(),
            "escaped from {o} along {d}"
        );
    }
}

/// Where the segment `a -> b` crosses the plane `x = x`.
fn crossing(a: Vec3, b: Vec3, x: f32) -> Vec3 {
    a + (b - a) * ((x - a.x) / (b.x - a.x))
}

#[test]
fn the_camera_sees_no_light_and_its_room_is_lit_only_through_the_doorway() {
    let scene = door();
    let device = Device::new().unwrap();
    let rt = scene.embree_geometry(&device).unwrap();
    let rays = CameraRays::new(&scene.camera().unwrap(), 64, 64);
    let (lo, hi) = light_box(&scene);
    let (mut room_a, mut lit, mut connections) = (0, 0, 0);
    for y in 0..64 {
        for x in 0..64 {
            let ray = rays.ray(x as f32 + 0.5, y as f32 + 0.5);
            let h = rt.intersect(&ray).expect("the rooms are closed");
            let m = &scene.materials()[h.material as usize];
            assert!(m.emission.is_none(), "pixel ({x}, {y}) sees the light");
            let p = ray.at(h.t);
            if p.x >= WALL_X.0 {
                continue; // the partition or room B, through the doorway
            }
            room_a += 1;
            let n = h.facing(ray.dir.normalize());
            let mut seen = false;
            // A 6 x 6 grid of points on the panel, 1 cm in from its edges.
            for i in 0..36 {
                let t = Vec3::new((i % 6) as f32 / 5.0, 0.0, (i / 6) as f32 / 5.0);
                let q = lo + Vec3::ONE + (hi - lo - 2.0 * Vec3::ONE) * t;
                let q = Vec3::new(q.x, lo.y, q.z);
                if rt.occluded(&Ray::segment(p + n * 0.01, q, 1e-4)) {
                    continue;
                }
                connections += 1;
                seen = true;
                // Through the doorway, at both faces of the wall.
                for wall in [WALL_X.0, WALL_X.1] {
                    let c = crossing(p, q, wall);
                    assert!(
                        c.y <= DOORWAY_TOP && (DOORWAY_Z.0..=DOORWAY_Z.1).contains(&c.z),
                        "light reaches {p} past the doorway at {c}"
                    );
                }
            }
            lit += usize::from(seen);
        }
    }
    eprintln!("room A pixels {room_a}, directly lit {lit}, light connections {connections}");
    assert!(room_a > 64 * 64 / 2, "the camera looks into its own room");
    assert!(lit > 0, "some light comes through the gap");
    assert!(
        lit * 10 < room_a,
        "only a sliver of room A sees the light: {lit} of {room_a}"
    );
}

#[test]
fn light_reaches_the_camera_room_in_both_renderers() {
    let device = Device::new().unwrap();
    let prepared = Arc::new(door().commit(&device).unwrap());
    let mut cfg = TraceConfig::new(Mode::Classic, Budget::NMax(20_000));
    cfg.seed = crate::common::seed(5);
    let records = Tracer::new(Arc::clone(&prepared))
        .trace(&cfg)
        .unwrap()
        .records();
    let in_a = records.iter().filter(|r| r.position.x < WALL_X.0).count();
    eprintln!("{in_a} of {} photons stored in room A", records.len());
    assert!(
        in_a > 0 && in_a * 4 < records.len(),
        "{in_a} of {}",
        records.len()
    );
    let maps = RenderMaps::build(&records);
    let mut rc = RenderConfig::new(16, 16);
    rc.spp = 4;
    let photon = render(&prepared, Some(&maps), &rc).unwrap();
    rc.spp = 16;
    let path = render_path(&prepared, &rc, PathPart::Full).unwrap();
    let (a, b) = (photon.mean(), path.mean());
    eprintln!("image mean: photon render {a}, path tracer {b}");
    assert!(a.min_element() > 0.0 && b.min_element() > 0.0);
}

/// Per-channel flux of the photons stored at `depth`.
fn flux_at(records: &[adaptive_pm::photon_map::PhotonRecord], depth: u8) -> Vec3 {
    let sum = records
        .iter()
        .filter(|r| r.depth == depth)
        .fold(glam::DVec3::ZERO, |a, r| a + r.power.as_dvec3());
    sum.as_vec3()
}

/// Classic photons all land (the scene is closed), so the first hits hold
/// the light's whole power, exactly up to the 1/512 power quantisation;
/// each bounce keeps an albedo's share of it, between the smallest and the
/// largest albedo of the scene (per channel, within 4 sigma of the seeds'
/// scatter).
#[test]
fn stored_flux_is_the_light_power_and_the_albedos_bound_its_bounces() {
    let scene = door();
    let power = scene.lights()[0].power();
    let albedos: Vec<Vec3> = scene
        .materials()
        .iter()
        .map(|m| match &m.brdf {
            Brdf::Lambert(l) => l.albedo,
            other => panic!("not diffuse: {other:?}"),
        })
        .collect();
    let a_min = albedos.iter().fold(Vec3::ONE, |a, &b| a.min(b));
    let a_max = albedos.iter().fold(Vec3::ZERO, |a, &b| a.max(b));
    let device = Device::new().unwrap();
    let tracer = Tracer::new(scene.commit(&device).unwrap());
    let seeds = 4;
    let mut ratios = Vec::new();
    for s in 0..seeds {
        let mut cfg = TraceConfig::new(Mode::Classic, Budget::NMax(10_000));
        cfg.seed = crate::common::seed(100 + s);
        let records = tracer.trace(&cfg).unwrap().records();
        let (f0, f1) = (flux_at(&records, 0), flux_at(&records, 1));
        let rel = (f0 / power - Vec3::ONE).abs().max_element();
        assert!(
            rel < 1.0 / 256.0,
            "first-hit flux {f0} against power {power}"
        );
        ratios.push(f1 / f0);
    }
    let mean = ratios.iter().copied().sum::<Vec3>() / seeds as f32;
    let var = ratios
        .iter()
        .map(|r| (*r - mean) * (*r - mean))
        .sum::<Vec3>()
        / (seeds - 1) as f32;
    let se = (var / seeds as f32).powf(0.5);
    eprintln!("bounce ratio {mean} +- {se}, albedos {a_min} .. {a_max}");
    for c in 0..3 {
        // How far the ratio lies outside the albedos' range (0 inside it).
        let outside = (a_min[c] - mean[c]).max(mean[c] - a_max[c]).max(0.0);
        crate::common::assert_sigmas(
            &format!("bounce ratio channel {c} within the albedos"),
            f64::from(outside),
            f64::from(se[c]),
            4.0,
        );
    }
}
