//! The scene model and glTF loading: the built-in Cornell box against its
//! published numbers and against the asset file, and bad input.

use adaptive_pm::scene::{Light, Scene};
use adaptive_pm::Error;
use glam::Vec3;
use serde_json::json;
use std::f32::consts::PI;
use std::path::{Path, PathBuf};

use crate::common;

fn asset() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell_box.gltf")
}

#[test]
fn cornell_matches_the_published_box() {
    let s = Scene::cornell().unwrap();
    assert_eq!(s.meshes().len(), 8);
    // 6 quads + 2 blocks of 5 quads, 2 triangles each
    assert_eq!(s.triangle_count(), 32);
    assert_eq!(s.skipped_degenerate(), 0);
    assert_eq!(s.lights().len(), 1);
    let Light::Area(l) = &s.lights()[0] else {
        panic!("the light is an area light")
    };
    assert!((l.area - 130.0 * 105.0).abs() < 1e-2, "{}", l.area);
    // diffuse: power = pi A L
    let expect = Vec3::new(17.0, 12.0, 4.0) * PI * 130.0 * 105.0;
    assert!((s.lights()[0].power() - expect).abs().max_element() < 1e-3 * expect.max_element());
    // it faces down
    let p = s.lights()[0].sample(0.3, [0.2, 0.7], [0.1, 0.1]);
    assert!(p.normal.unwrap().y < -0.999 && p.direction.y < 0.0);
    let cam = s.camera().unwrap();
    assert!((cam.eye - Vec3::new(278.0, 273.0, -800.0)).length() < 1e-3);
    assert!((cam.forward - Vec3::Z).length() < 1e-5, "{}", cam.forward);
    assert!((cam.vfov_deg - 39.3077).abs() < 1e-3);
    let (lo, hi) = s.bounds();
    assert!(
        lo.abs_diff_eq(Vec3::ZERO, 1e-3) && hi.abs_diff_eq(Vec3::new(556.0, 548.8, 559.2), 1e-3)
    );
    let white = s.materials().iter().find(|m| m.name == "white").unwrap();
    assert!(white.emission.is_none());
}

#[test]
fn cosn_power_is_exact() {
    let mut s = Scene::cornell().unwrap();
    let p0 = s.lights()[0].power();
    for n in [1.0f32, 10.0, 200.0] {
        s.set_cosn(adaptive_pm::emitter::CosN::new(n).unwrap());
        // power scales by 2 / (n + 2) relative to the diffuse light
        let ratio = s.lights()[0].power().x / p0.x;
        assert!(
            (ratio - 2.0 / (n + 2.0)).abs() < 1e-5,
            "n={n} ratio={ratio}"
        );
    }
}

#[test]
fn builtin_equals_asset_file() {
    let a = Scene::cornell().unwrap();
    let b = Scene::load(asset()).unwrap();
    assert_eq!(a.meshes(), b.meshes());
    assert_eq!(a.materials(), b.materials());
    assert_eq!(a.lights(), b.lights());
    assert_eq!(a.camera(), b.camera());
    assert!(matches!(Scene::open("cornell"), Ok(s) if s.meshes() == a.meshes()));
}

fn cornell_json() -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(asset()).unwrap()).unwrap()
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

#[test]
fn missing_truncated_and_garbage_files_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let e = Scene::load(dir.path().join("nope.gltf")).unwrap_err();
    assert!(
        matches!(e, Error::Io { .. }) && e.to_string().contains("nope.gltf"),
        "{e}"
    );

    let full = std::fs::read(asset()).unwrap();
    let p = write(dir.path(), "trunc.gltf", &full[..full.len() / 2]);
    let e = Scene::load(&p).unwrap_err();
    assert!(
        matches!(e, Error::Load { .. }) && e.to_string().contains("trunc.gltf"),
        "{e}"
    );

    let p = write(
        dir.path(),
        "garbage.glb",
        b"glTF\x02\x00\x00\x00garbage that is not a glb at all",
    );
    assert!(matches!(Scene::load(&p), Err(Error::Load { .. })));
    let p = write(dir.path(), "empty.gltf", b"");
    assert!(matches!(Scene::load(&p), Err(Error::Load { .. })));
}

#[test]
fn a_scene_without_light_loads_but_does_not_trace_until_it_has_one() {
    let dir = tempfile::tempdir().unwrap();
    let mut doc = cornell_json();
    let light = doc["materials"].as_array_mut().unwrap().last_mut().unwrap();
    light.as_object_mut().unwrap().remove("emissiveFactor");
    let p = write(dir.path(), "dark.gltf", doc.to_string().as_bytes());
    let mut scene = Scene::load(&p).unwrap();
    assert!(scene.lights().is_empty());
    let e = scene.validate().unwrap_err();
    assert!(
        matches!(e, Error::InvalidScene(_)) && e.to_string().contains("no light"),
        "{e}"
    );
    let device = adaptive_pm::embree::Device::new().unwrap();
    let e = scene.clone().commit(&device).unwrap_err();
    assert!(e.to_string().contains("no light"), "{e}");
    scene
        .add_light(adaptive_pm::scene::Light::Point(
            adaptive_pm::scene::PointLight {
                position: glam::Vec3::new(278.0, 500.0, 279.0),
                intensity: glam::Vec3::splat(1e4),
            },
        ))
        .unwrap();
    scene.validate().unwrap();
    assert!(scene.commit(&device).is_ok());
}

#[test]
fn bad_cosn_exponents_are_rejected() {
    let dir = tempfile::tempdir().unwrap();
    for bad in [json!(-1.0), json!("ten")] {
        let mut doc = cornell_json();
        doc["materials"][3]["extras"]["cosn"] = bad.clone();
        let p = write(dir.path(), "bad.gltf", doc.to_string().as_bytes());
        let e = Scene::load(&p).unwrap_err();
        assert!(matches!(e, Error::InvalidParameter { .. }), "{bad}: {e}");
    }
    let mut doc = cornell_json();
    doc["materials"][3]["extras"]["cosn"] = json!(50.0);
    let p = write(dir.path(), "ok.gltf", doc.to_string().as_bytes());
    let loaded = Scene::load(&p).unwrap();
    let Light::Area(l) = &loaded.lights()[0] else {
        unreachable!()
    };
    assert_eq!(l.emission.profile.exponent(), 50.0);
    assert!(adaptive_pm::emitter::CosN::new(f32::NAN).is_err());
}

/// A one-triangle-pair glTF with an external buffer, for hand-made geometry.
fn quad_file(dir: &Path, verts: &[[f32; 3]], idx: &[u32], emissive: bool) -> PathBuf {
    let mut bin = Vec::new();
    for v in verts {
        for c in v {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    let off = bin.len();
    for i in idx {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    std::fs::write(dir.join("quad.bin"), &bin).unwrap();
    let mut mat = json!({"name": "m", "pbrMetallicRoughness": {"metallicFactor": 0.0}});
    if emissive {
        mat["emissiveFactor"] = json!([1.0, 1.0, 1.0]);
    }
    let doc = json!({
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "materials": [mat],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": verts.len(), "type": "VEC3", "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 1.0]},
            {"bufferView": 1, "componentType": 5125, "count": idx.len(), "type": "SCALAR"}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": off},
            {"buffer": 0, "byteOffset": off, "byteLength": bin.len() - off}],
        "buffers": [{"byteLength": bin.len(), "uri": "quad.bin"}]
    });
    write(dir, "quad.gltf", doc.to_string().as_bytes())
}

#[test]
fn nan_positions_are_an_error_and_degenerate_triangles_are_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let quad = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let mut nan = quad;
    nan[2][1] = f32::NAN;
    let e = Scene::load(quad_file(dir.path(), &nan, &[0, 1, 2, 0, 2, 3], true)).unwrap_err();
    assert!(
        matches!(e, Error::InvalidScene(_)) && e.to_string().contains("non-finite"),
        "{e}"
    );
    let mut inf = quad;
    inf[0][0] = f32::INFINITY;
    assert!(Scene::load(quad_file(dir.path(), &inf, &[0, 1, 2, 0, 2, 3], true)).is_err());

    // two real triangles + two with zero area (a repeated vertex, collinear points)
    let s = Scene::load(quad_file(
        dir.path(),
        &quad,
        &[0, 1, 2, 0, 2, 3, 0, 0, 1, 0, 1, 1],
        true,
    ))
    .unwrap();
    assert_eq!(s.triangle_count(), 2);
    assert_eq!(s.skipped_degenerate(), 2);
    assert!((s.lights()[0].area().unwrap() - 1.0).abs() < 1e-6);

    let e = Scene::load(quad_file(dir.path(), &quad, &[0, 1, 7], true)).unwrap_err();
    assert!(matches!(e, Error::InvalidScene(_)), "{e}");
}

#[test]
fn surface_points_are_area_uniform_and_fixed_by_seed() {
    let s = Scene::cornell().unwrap();
    let sampler = s.surface_sampler();
    let (seed, other) = (common::seed(1), common::seed(2));
    let a = sampler.points(20_000, seed);
    assert_eq!(a, sampler.points(20_000, seed));
    assert_ne!(a[..10], sampler.points(10, other)[..]);
    // The floor's share of points matches its share of area: the points are
    // independent (point i depends only on the seed and i), so the share's
    // standard error is measured from the points' floor indicators; 5 sigma.
    let floor = s
        .meshes()
        .iter()
        .position(|m| m.name.starts_with("floor"))
        .unwrap();
    let frac = s.meshes()[floor].area() / sampler.total_area();
    let share = common::MeanVar::of(a.iter().map(|p| f64::from(u8::from(p.mesh == floor))));
    common::assert_sigmas(
        "floor share of surface points",
        share.mean() - frac,
        share.std_error(),
        5.0,
    );
}
