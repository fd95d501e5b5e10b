//! Normal textures as oracles: MikkTSpace's tangent on a flat floor is its
//! texture's u gradient, a texel tilts the shading normal by the tangent
//! frame (glTF's `(2 rgb - 1) (scale, scale, 1)`), a glTF `TANGENT` and a
//! mirrored node give the same frame rules, the path tracer's and the
//! renderer's direct light follow the mapped normal's cosine exactly (a
//! delta light), and photons reflected through a mapped normal carry the
//! flux that the camera side's equation gives, `rho cos(t) (1 + cos(t)) / 2`
//! of what they bring, within the noise the test measures.

use adaptive_pm::brdf::{GltfMaterial, Lambert};
use adaptive_pm::embree::Device;
use adaptive_pm::emitter::CosN;
use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
use adaptive_pm::raycast::Ray;
use adaptive_pm::render::{render, PathPart, PathTracer, RenderConfig, View};
use adaptive_pm::rng::Rng;
use adaptive_pm::scene::{
    Camera, DirectionalLight, Emission, Light, MaterialMaps, NormalMap, Sampler, Scene,
    TexTransform, Texture, TextureRef,
};
use glam::{Vec3, Vec4};
use serde_json::json;
use std::f32::consts::PI;

use crate::common::{self, assert_sigmas, MeanVar};
use crate::gltf_doc::{square, Doc};

const ALBEDO: f32 = 0.8;
/// The tilt the texel encodes, towards +u (the floor's +x).
const TILT_DEG: f32 = 30.0;

/// The RGBA texel of a unit normal tilted by `deg` towards the tangent.
fn tilted_texel(deg: f32) -> [u8; 4] {
    let (s, c) = deg.to_radians().sin_cos();
    let byte = |v: f32| ((v + 1.0) / 2.0 * 255.0).round() as u8;
    [byte(s), 128, byte(c), 255]
}

/// The tangent-space normal an 8-bit texel decodes to (before scale).
fn decoded(t: [u8; 4]) -> Vec3 {
    Vec3::new(t[0] as f32, t[1] as f32, t[2] as f32) / 255.0 * 2.0 - Vec3::ONE
}

/// What the shading normal of the floor must be: T = +x, B = +z (the v
/// gradient), N = +y.
fn expected_normal(t: [u8; 4], scale: f32) -> Vec3 {
    let n = decoded(t);
    (Vec3::X * n.x * scale + Vec3::Z * n.y * scale + Vec3::Y * n.z).normalize()
}

/// A `half`-sized floor at y = 0 facing +y, u along +x and v along +z,
/// whose material is white Lambert with a 1 x 1 normal texture `texel`.
fn add_mapped_floor(s: &mut Scene, half: f32, texel: [u8; 4], scale: f32) -> usize {
    if s.lights().is_empty() {
        let sun = DirectionalLight::new(-Vec3::Y, Vec3::ONE);
        s.add_light(Light::Directional(sun)).unwrap();
    }
    let m = s.add_material(adaptive_pm::scene::Material {
        name: "floor".into(),
        brdf: Lambert::new(Vec3::splat(ALBEDO)).unwrap().into(),
        emission: None,
    });
    let texture = s.add_texture(Texture::new(1, 1, vec![texel], Sampler::default()).unwrap());
    let positions = vec![
        Vec3::new(-half, 0.0, -half),
        Vec3::new(half, 0.0, -half),
        Vec3::new(half, 0.0, half),
        Vec3::new(-half, 0.0, half),
    ];
    let mesh = s
        .add_mesh("floor", positions, vec![[0, 3, 2], [0, 2, 1]], m)
        .unwrap();
    let uv = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    s.set_texcoords(mesh, 0, uv.iter().map(|&a| a.into()).collect())
        .unwrap();
    let maps = MaterialMaps {
        normal: Some(NormalMap {
            texture: TextureRef {
                texture,
                tex_coord: 0,
                transform: TexTransform::default(),
            },
            scale,
        }),
        ..MaterialMaps::new(GltfMaterial::new(Vec3::splat(ALBEDO), 0.0, 1.0))
    };
    s.set_material_maps(m, maps).unwrap();
    s.generate_tangents(mesh, 0).unwrap();
    mesh
}

fn hit_normal(scene: &Scene, x: f32, z: f32) -> Vec3 {
    let device = Device::new().unwrap();
    let prepared = scene.clone().commit(&device).unwrap();
    let ray = Ray::new(Vec3::new(x, 0.5, z), -Vec3::Y);
    let hit = adaptive_pm::raycast::RayCaster::intersect(prepared.caster(), &ray).unwrap();
    scene.shading_normal(&hit).unwrap()
}

#[test]
fn mikktspace_gives_a_flat_floor_its_uv_gradient_as_tangent() {
    let mut s = Scene::new();
    let mesh = add_mapped_floor(&mut s, 1.0, tilted_texel(TILT_DEG), 1.0);
    let tangents = &s.meshes()[mesh].tangents;
    assert_eq!(tangents.len(), 2);
    for t in tangents.iter().flatten() {
        // B = (N x T) w = (y x x) w = -z w must be +z, the v gradient.
        assert!((*t - Vec4::new(1.0, 0.0, 0.0, -1.0)).length() < 1e-5, "{t}");
    }
}

#[test]
fn a_texel_tilts_the_shading_normal_in_the_tangent_frame() {
    for (texel, scale) in [
        (tilted_texel(TILT_DEG), 1.0),
        (tilted_texel(TILT_DEG), 0.5),
        ([128, 200, 230, 255], 1.0),
        ([128, 128, 255, 255], 1.0),
    ] {
        let mut s = Scene::new();
        add_mapped_floor(&mut s, 1.0, texel, scale);
        for (x, z) in [(0.3, -0.4), (-0.7, 0.6)] {
            let n = hit_normal(&s, x, z);
            let want = expected_normal(texel, scale);
            assert!(
                (n - want).length() < 1e-5,
                "{texel:?} x{scale}: {n} vs {want}"
            );
        }
    }
}

/// The floor lit by a Sun at 40 degrees from the vertical in the x-y plane,
/// coming from +x or -x: the mapped normal (tilted towards +x) sees it at
/// 10 or 70 degrees.
fn sunlit_mapped_floor(from_plus_x: bool) -> (Scene, Vec3) {
    let mut s = Scene::new();
    let a = 40f32.to_radians();
    let sign = if from_plus_x { -1.0 } else { 1.0 };
    let toward = Vec3::new(sign * a.sin(), -a.cos(), 0.0);
    let e = Vec3::new(1.0, 0.9, 0.8);
    s.add_light(Light::Directional(DirectionalLight::new(toward, e)))
        .unwrap();
    add_mapped_floor(&mut s, 1.0, tilted_texel(TILT_DEG), 1.0);
    let n = expected_normal(tilted_texel(TILT_DEG), 1.0);
    (s, e * (ALBEDO / PI) * (-toward).dot(n).max(0.0))
}

fn close(a: Vec3, b: Vec3, rel: f32) -> bool {
    (a - b).abs().max_element() <= rel * b.abs().max_element()
}

#[test]
fn the_path_tracer_lights_the_floor_by_the_mapped_cosine() {
    let device = Device::new().unwrap();
    for from_plus_x in [true, false] {
        let (scene, want) = sunlit_mapped_floor(from_plus_x);
        let prepared = scene.commit(&device).unwrap();
        let paths = PathTracer::new(&prepared);
        let mut rng = Rng::new(3);
        for (x, z) in [(0.0, 0.0), (0.5, -0.3), (-0.6, 0.7)] {
            let ray = Ray::new(Vec3::new(x, 0.5, z), -Vec3::Y);
            let l = paths.radiance(ray, PathPart::Direct, false, &mut rng);
            assert!(close(l, want, 1e-5), "from +x {from_plus_x}: {l} vs {want}");
        }
    }
}

#[test]
fn the_renderer_lights_the_floor_by_the_mapped_cosine() {
    let device = Device::new().unwrap();
    let (scene, want) = sunlit_mapped_floor(true);
    let prepared = scene.commit(&device).unwrap();
    let mut cfg = RenderConfig::new(6, 6);
    cfg.view = View::DirectOnly;
    cfg.spp = 2;
    // Straight down from y = 2 at a narrow field: every pixel sees the floor.
    cfg.camera =
        Some(Camera::look_at(Vec3::new(0.0, 2.0, 0.0), Vec3::ZERO, Vec3::Z, 20.0).unwrap());
    let image = render(&prepared, None, &cfg).unwrap();
    for y in 0..6 {
        for x in 0..6 {
            let p = image.pixel(x, y);
            assert!(close(p, want, 1e-4), "pixel ({x}, {y}): {p} vs {want}");
        }
    }
}

/// A black closed box [-1, 1] x [0, 2] x [-1, 1] whose floor is the mapped
/// white floor, and a near-collimated lamp (cos^n, n = 1e5) facing down
/// from y = 1.9. Every photon hits the floor first; what the floor
/// reflects is stored at its first (black) hit.
fn boxed_floor() -> Scene {
    let mut s = Scene::new();
    add_mapped_floor(&mut s, 1.0, tilted_texel(TILT_DEG), 1.0);
    // The floor's own Sun gives way to the lamp below.
    s.clear_lights();
    let black = s.add_material(adaptive_pm::scene::Material {
        name: "black".into(),
        brdf: Lambert::new(Vec3::ZERO).unwrap().into(),
        emission: None,
    });
    let (lo, hi) = (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 2.0, 1.0));
    let corner = |i: u32| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    let positions: Vec<Vec3> = (0..8).map(corner).collect();
    // The four walls and the ceiling (the floor is the mapped mesh).
    let faces = [
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 5, 7, 3],
        [0, 1, 3, 2],
        [4, 6, 7, 5],
    ];
    let indices = faces
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    s.add_mesh("walls", positions, indices, black).unwrap();
    let lamp = s.add_material(adaptive_pm::scene::Material {
        name: "lamp".into(),
        brdf: Lambert::new(Vec3::ZERO).unwrap().into(),
        emission: Some(Emission::new(Vec3::ONE, CosN::new(1e5).unwrap())),
    });
    let y = 1.9;
    let q = [
        Vec3::new(-0.1, y, -0.1),
        Vec3::new(0.1, y, -0.1),
        Vec3::new(0.1, y, 0.1),
        Vec3::new(-0.1, y, 0.1),
    ];
    // (q1 - q0) x (q3 - q0) = x cross z = -y: [0, 1, 2] faces down.
    s.add_mesh("lamp", q.to_vec(), vec![[0, 1, 2], [0, 2, 3]], lamp)
        .unwrap();
    s
}

/// Photons brought straight down onto a normal tilted by t leave with
/// `rho cos(t) (1 + cos(t)) / 2` of their flux: the camera side's floor
/// radiance `rho E cos(t) / pi`, integrated over the directions above both
/// the floor and the shading normal (a projected solid angle of
/// `pi (1 + cos t) / 2`). Without the adjoint factor photons would carry
/// `rho (1 + cos t) / 2`; with none of the shading normal, `rho`.
#[test]
fn photons_reflect_the_flux_the_camera_side_equation_gives() {
    let scene = boxed_floor();
    let device = Device::new().unwrap();
    let tracer = Tracer::new(scene.commit(&device).unwrap());
    let mut cfg = TraceConfig::new(Mode::Classic, Budget::NMax(200_000));
    cfg.seed = common::seed(11);
    let out = tracer.trace(&cfg).unwrap();
    let records = out.records();
    let mut depths = std::collections::BTreeMap::new();
    for r in &records {
        *depths.entry(r.depth).or_insert(0usize) += 1;
    }
    eprintln!("stored by depth {depths:?}");
    let flux = |r: &adaptive_pm::photon_map::PhotonRecord| {
        f64::from(r.power.x + r.power.y + r.power.z) / 3.0
    };
    let arrived: Vec<f64> = records.iter().filter(|r| r.depth == 0).map(flux).collect();
    assert!(
        arrived.len() > 100_000,
        "{} photons on the floor",
        arrived.len()
    );
    let per_photon = arrived.iter().sum::<f64>() / arrived.len() as f64;
    // One photon arrives per emitted photon, and each leaves 0 or 1 child
    // (classic mode): the children's flux, with zeros for the others, is
    // one sample per arrival.
    let mut reflected = MeanVar::default();
    for r in records.iter().filter(|r| r.depth == 1) {
        reflected.push(flux(r) / per_photon);
    }
    for _ in reflected.count()..arrived.len() as u64 {
        reflected.push(0.0);
    }
    let c = f64::from(expected_normal(tilted_texel(TILT_DEG), 1.0).y);
    let want = f64::from(ALBEDO) * c * (1.0 + c) / 2.0;
    eprintln!(
        "reflected {:.5} +- {:.5}, want {want:.5}",
        reflected.mean(),
        reflected.std_error()
    );
    assert_sigmas(
        "reflected flux through a mapped normal",
        reflected.mean() - want,
        reflected.std_error(),
        4.0,
    );
}

/// The same floor as a glTF file with a `TANGENT` attribute (w = -1, as
/// MikkTSpace gives it), and mirrored by a node scaled -1 in x: the
/// mirror flips the handedness, so B stays the v gradient, and the tilt
/// towards +u becomes a tilt towards -x.
#[test]
fn a_gltf_tangent_and_a_mirrored_node_keep_the_frame_rules() {
    let texel = tilted_texel(TILT_DEG);
    let want = expected_normal(texel, 1.0);
    for (tangent, mirrored) in [(true, false), (false, false), (true, true), (false, true)] {
        let mut doc = Doc::default();
        let png = crate::gltf_textures::png_rgb(1, 1, &[[texel[0], texel[1], texel[2]]]);
        let tex = doc.texture(&png, json!({}));
        let m = doc.material(json!({"name": "floor", "normalTexture": {"index": tex},
            "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0}}));
        let (p, i) = square(1.0, true);
        let f = doc.mesh(&p, &i, 4, Some(m));
        // square(): (-1, -1), (1, -1), (1, 1), (-1, 1) in (x, z).
        doc.texcoords(f, &[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        if tangent {
            doc.tangents(f, &[[1.0, 0.0, 0.0, -1.0]; 4]);
        }
        let node = if mirrored {
            json!({"mesh": f, "scale": [-1.0, 1.0, 1.0]})
        } else {
            json!({"mesh": f})
        };
        doc.node(node);
        add_lamp(&mut doc);
        let dir = tempfile::tempdir().unwrap();
        let scene = Scene::load(doc.write(dir.path())).unwrap();
        let n = hit_normal(&scene, 0.2, 0.3);
        let want = if mirrored {
            want * Vec3::new(-1.0, 1.0, 1.0)
        } else {
            want
        };
        assert!(
            (n - want).length() < 1e-5,
            "TANGENT {tangent}, mirrored {mirrored}: {n} vs {want}"
        );
        assert!(
            !scene.warnings().iter().any(|w| w.contains("normalTexture")),
            "{:?}",
            scene.warnings()
        );
    }
}

/// A lamp facing down at y = 3.
fn add_lamp(doc: &mut Doc) {
    let lamp = doc.material(json!({"name": "lamp", "emissiveFactor": [1.0, 1.0, 1.0]}));
    let (p, i) = square(0.5, false);
    let l = doc.mesh(&p, &i, 4, Some(lamp));
    doc.node(json!({"mesh": l, "translation": [0.0, 3.0, 0.0]}));
}

#[test]
fn bad_normal_textures_are_refused_or_warned_by_name() {
    let mut doc = Doc::default();
    let png = crate::gltf_textures::png_rgb(1, 1, &[[128, 128, 255]]);
    let tex = doc.texture(&png, json!({}));
    let m = doc.material(
        json!({"name": "bumpy", "normalTexture": {"index": tex, "texCoord": 1},
        "pbrMetallicRoughness": {"metallicFactor": 0.0}}),
    );
    let (p, i) = square(1.0, true);
    let f = doc.mesh(&p, &i, 4, Some(m));
    doc.texcoords(f, &[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
    doc.node(json!({"mesh": f}));
    add_lamp(&mut doc);
    let dir = tempfile::tempdir().unwrap();
    let err = Scene::load(doc.write(dir.path())).unwrap_err().to_string();
    assert!(err.contains("TEXCOORD_1"), "{err}");
    // Texture coordinates that are all equal give MikkTSpace nothing: the
    // (valid) file loads, warned, with its normals unbent.
    let mut doc = Doc::default();
    let tex = doc.texture(&png, json!({}));
    let m = doc.material(json!({"name": "bumpy", "normalTexture": {"index": tex},
        "pbrMetallicRoughness": {"metallicFactor": 0.0}}));
    let f = doc.mesh(&p, &i, 4, Some(m));
    doc.texcoords(f, &[[0.5, 0.5]; 4]);
    doc.node(json!({"mesh": f}));
    add_lamp(&mut doc);
    let scene = Scene::load(doc.write(dir.path())).unwrap();
    let warned = scene.warnings().join("\n");
    assert!(
        warned.contains("MikkTSpace") && warned.contains("not applied"),
        "{warned}"
    );
    assert!((hit_normal(&scene, 0.1, 0.2) - Vec3::Y).length() < 1e-6);
    // A transform that is not finite (JSON has no NaN: a huge number overflows f32).
    let mut doc = Doc::default();
    let tex = doc.texture(&png, json!({}));
    let m = doc.material(json!({"name": "bumpy", "normalTexture": {"index": tex,
        "extensions": {"KHR_texture_transform": {"scale": [1e300, 1.0]}}},
        "pbrMetallicRoughness": {"metallicFactor": 0.0}}));
    let f = doc.mesh(&p, &i, 4, Some(m));
    doc.texcoords(f, &[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
    doc.node(json!({"mesh": f}));
    add_lamp(&mut doc);
    let err = Scene::load(doc.write(dir.path())).unwrap_err().to_string();
    assert!(
        err.contains("bumpy") && err.contains("KHR_texture_transform"),
        "{err}"
    );
}
