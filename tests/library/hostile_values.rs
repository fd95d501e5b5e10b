//! Hostile magnitudes: lights whose powers would overflow (or vanish in)
//! the f32 arithmetic downstream are refused with a clear error, and a
//! render that meets a sample beyond f32 says so (`dropped_samples`)
//! instead of printing null or zero means. Also: path-traced tiles are the
//! whole image's rows.

use adaptive_pm::brdf::Lambert;
use adaptive_pm::embree::Device;
use adaptive_pm::emitter::CosN;
use adaptive_pm::render::{
    render_path, render_path_with, render_with, PathPart, RenderConfig, View,
};
use adaptive_pm::scene::{
    Camera, Emission, Light, Material, PointLight, Scene, MAX_LIGHT_POWER, MIN_LIGHT_POWER,
};
use adaptive_pm::Error;
use glam::Vec3;
use std::f32::consts::PI;

use crate::common;
use std::sync::Arc;

/// A white Lambert square of side `side` in the z = 0 plane, facing +z.
fn floor(side: f32) -> Scene {
    let mut s = Scene::new();
    let white = s.add_material(Material {
        name: "white".into(),
        brdf: Lambert::new(Vec3::splat(0.8)).unwrap().into(),
        emission: None,
    });
    let h = side / 2.0;
    let positions = vec![
        Vec3::new(-h, -h, 0.0),
        Vec3::new(h, -h, 0.0),
        Vec3::new(h, h, 0.0),
        Vec3::new(-h, h, 0.0),
    ];
    s.add_mesh("floor", positions, vec![[0, 1, 2], [0, 2, 3]], white)
        .unwrap();
    s
}

fn point(z: f32, intensity: f32) -> Light {
    Light::Point(PointLight {
        position: Vec3::new(0.0, 0.0, z),
        intensity: Vec3::splat(intensity),
    })
}

fn message(e: Error) -> String {
    let msg = e.to_string();
    assert!(matches!(e, Error::InvalidScene(_)), "{msg}");
    msg
}

#[test]
fn a_light_above_the_power_limit_is_refused() {
    let mut s = floor(1.0);
    // Power 4 pi I: just below and just above the limit.
    let at_limit = MAX_LIGHT_POWER / (4.0 * PI) * 0.99;
    s.add_light(point(1.0, at_limit)).unwrap();
    let msg = message(s.add_light(point(1.0, at_limit * 1.02)).unwrap_err());
    assert!(msg.contains("above 1e30 W"), "{msg}");
}

#[test]
fn lights_whose_total_power_overflows_are_refused() {
    // Forty lights, each within the limit; together 40x it. In f32 the
    // total of forty 1.3e38 W lights was infinite, and renders null.
    let mut s = floor(1.0);
    let each = MAX_LIGHT_POWER / (4.0 * PI) * 0.9;
    for _ in 0..40 {
        s.add_light(point(1.0, each)).unwrap();
    }
    let msg = message(s.validate().unwrap_err());
    assert!(msg.contains("total power"), "{msg}");
}

#[test]
fn an_emitter_brighter_than_the_radiance_limit_is_refused() {
    let mut s = floor(1.0);
    let lamp = s.add_material(Material {
        name: "lamp".into(),
        brdf: Lambert::new(Vec3::ZERO).unwrap().into(),
        emission: Some(Emission::new(Vec3::splat(1e38), CosN::new(1.0).unwrap())),
    });
    let quad = vec![
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(1e-3, 0.0, 1.0),
        Vec3::new(0.0, 1e-3, 1.0),
    ];
    let msg = message(s.add_mesh("lamp", quad, vec![[0, 2, 1]], lamp).unwrap_err());
    assert!(
        msg.contains("radiance [1e38, 1e38, 1e38] above 1e30"),
        "{msg}"
    );
}

#[test]
fn dark_and_vanishing_lights() {
    // Below the floor, flush-to-zero made the light emit no photon at all.
    let mut s = floor(1.0);
    let tiny = MIN_LIGHT_POWER / (4.0 * PI) * 0.5;
    let msg = message(s.add_light(point(1.0, tiny)).unwrap_err());
    assert!(msg.contains("below 1e-20 W"), "{msg}");

    // A dark light is allowed, but not as the only light.
    s.add_light(point(1.0, 0.0)).unwrap();
    let msg = message(s.validate().unwrap_err());
    assert!(msg.contains("no light that emits"), "{msg}");
    s.add_light(point(1.0, 1.0)).unwrap();
    s.validate().unwrap();
}

/// A camera at height `z` above the origin, looking down at the floor.
fn look_down(s: &mut Scene, z: f32, vfov_deg: f32) {
    s.set_camera(Camera {
        eye: Vec3::new(0.0, 0.0, z),
        forward: Vec3::NEG_Z,
        up: Vec3::Y,
        vfov_deg,
    })
    .unwrap();
}

/// A square render of direct light only.
fn direct_only(side: u32, spp: u32) -> RenderConfig {
    let mut cfg = RenderConfig::new(side, side);
    cfg.spp = spp;
    cfg.view = View::DirectOnly;
    cfg
}

#[test]
fn samples_beyond_f32_are_counted_not_silently_dropped() {
    // A light 1e-7 above a floor 1e-6 wide: I / r^2 is about 1e42, beyond
    // f32, at every visible point. Before, those samples were dropped in
    // silence and the image read 0.
    let mut s = floor(1e-6);
    s.add_light(point(1e-7, 7e28)).unwrap();
    look_down(&mut s, 1e-5, 5.0);
    let prepared = s.commit(&Device::new().unwrap()).unwrap();
    let cfg = direct_only(8, 2);
    let (image, stats) = render_with(&prepared, None, None, &cfg, &|_, _| {}).unwrap();
    assert_eq!(stats.samples, 128);
    assert!(stats.dropped_samples > 0, "{stats:?}");
    assert!(image.pixels.iter().all(|p| p.is_finite()));
    let (image, stats) = render_path_with(&prepared, &cfg, PathPart::Full, &|_, _| {}).unwrap();
    assert!(stats.dropped_samples > 0, "{stats:?}");
    assert!(image.pixels.iter().all(|p| p.is_finite()));
}

#[test]
fn a_bright_but_representable_scene_drops_nothing() {
    // The Sun's power, 3.8e26 W, one unit above a floor: large, not overflowing.
    let mut s = floor(4.0);
    s.add_light(point(1.0, 3.8e26 / (4.0 * PI))).unwrap();
    look_down(&mut s, 3.0, 40.0);
    let prepared = s.commit(&Device::new().unwrap()).unwrap();
    let cfg = direct_only(9, 4);
    let (image, stats) = render_with(&prepared, None, None, &cfg, &|_, _| {}).unwrap();
    assert_eq!(stats.dropped_samples, 0);
    // Lambert floor under an isotropic point light: at the centre, straight
    // below it, L = (albedo / pi) I / h^2 (the centre pixel spans 0.24
    // units, where the cos^3 falloff stays within 2 % along the axes and
    // 4.2 % at the corners). Not statistical: a point light has no sampling
    // noise, so every sample of the pixel lies between 0.958 and 1 times L
    // wherever the jitter puts it, and so does their mean; 5 % holds for
    // any seed.
    let centre = image.pixels[4 * 9 + 4].x as f64;
    let expected = 0.8 / std::f64::consts::PI * 3.8e26 / (4.0 * std::f64::consts::PI);
    assert!(
        (centre / expected - 1.0).abs() < 0.05,
        "{centre:e} against {expected:e}"
    );
}

#[test]
fn path_traced_tiles_are_the_whole_image_rows() {
    let s = Scene::cornell().unwrap();
    let device = Device::new().unwrap();
    let prepared = Arc::new(s.clone().commit(&device).unwrap());
    let mut cfg = RenderConfig::new(12, 10);
    cfg.spp = 2;
    let whole = render_path(&prepared, &cfg, PathPart::Full).unwrap();
    let mut rows = Vec::new();
    for (y0, y1) in [(0, 3), (3, 10)] {
        cfg.rows = Some((y0, y1));
        let tile = render_path(&prepared, &cfg, PathPart::Full).unwrap();
        assert_eq!(tile.pixels.len(), 12 * (y1 - y0) as usize);
        rows.extend(tile.pixels);
    }
    assert_eq!(rows, whole.pixels);
}

/// Loads tests/hostile/base.gltf with `edit` applied to its JSON text.
fn load_edited(edit: impl Fn(String) -> String) -> adaptive_pm::Result<Scene> {
    let base = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/hostile/base.gltf");
    let text = edit(std::fs::read_to_string(base).unwrap());
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("edited.gltf");
    std::fs::write(&path, text).unwrap();
    Scene::load(&path)
}

fn load_error(edit: impl Fn(String) -> String) -> String {
    match load_edited(edit) {
        Ok(_) => panic!("the edited scene loaded"),
        Err(e) => common::chain(&e),
    }
}

#[test]
fn gltf_files_that_loaded_wrong_in_silence_are_refused() {
    load_edited(|t| t).unwrap();
    // A rotation of length 2 scaled the lamp by 4.
    let msg = load_error(|t| t.replace("\"rotation\":[1,0,0,0]", "\"rotation\":[2,0,0,0]"));
    assert!(
        msg.contains("node 1 (`lamp`)") && msg.contains("not a unit quaternion"),
        "{msg}"
    );
    // Within a rounding of unit length is fine.
    load_edited(|t| t.replace("\"rotation\":[1,0,0,0]", "\"rotation\":[1.0001,0,0,0]")).unwrap();
    // Required extensions the loader does not read: the geometry could be
    // compressed, or anything else.
    let required = |ext: &'static str| {
        move |t: String| t.replacen('{', &format!("{{\"extensionsRequired\": [\"{ext}\"], "), 1)
    };
    let msg = load_error(required("KHR_draco_mesh_compression"));
    assert!(
        msg.contains("requires the extension `KHR_draco_mesh_compression`"),
        "{msg}"
    );
    load_edited(required("KHR_materials_emissive_strength")).unwrap();
    // Five indices are one triangle and a remainder, dropped before.
    let msg = load_error(|t| t.replace("\"count\":6", "\"count\":5"));
    assert!(
        msg.contains("triangle list of 5 indices, not a multiple of 3"),
        "{msg}"
    );
}

/// A GLB file of tests/hostile/base.gltf's JSON (its buffer is a data: URI)
/// and `more` chunks after it, then `tail`; `declared` overrides the
/// header's total length.
fn glb(more: &[(u32, &[u8])], tail: &[u8], declared: Option<u32>) -> Vec<u8> {
    let base = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/hostile/base.gltf");
    let mut json = std::fs::read(base).unwrap();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let mut body = Vec::new();
    for (kind, data) in std::iter::once((0x4E4F_534A, &json[..])).chain(more.iter().copied()) {
        body.extend((data.len() as u32).to_le_bytes());
        body.extend(kind.to_le_bytes());
        body.extend(data);
    }
    body.extend(tail);
    let total = declared.unwrap_or(12 + body.len() as u32);
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(total.to_le_bytes());
    out.extend(body);
    out
}

fn load_glb(bytes: &[u8]) -> adaptive_pm::Result<Scene> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.glb");
    std::fs::write(&path, bytes).unwrap();
    Scene::load(&path)
}

#[test]
fn glb_files_whose_chunks_do_not_tile_the_file_are_refused() {
    const BIN: u32 = 0x004E_4942;
    load_glb(&glb(&[], &[], None)).unwrap();
    load_glb(&glb(&[(BIN, &[0; 8])], &[], None)).unwrap();
    let bad = [
        // The header's length hid what follows it.
        (
            glb(&[], &[0; 16], Some(12 + 8)),
            "the GLB header declares 20 bytes",
        ),
        // Bytes after the last chunk.
        (glb(&[], &[1, 2, 3], None), "truncated header"),
        // Two binary chunks: which one is the buffer?
        (
            glb(&[(BIN, &[0; 8]), (BIN, &[0; 8])], &[], None),
            "at most one BIN chunk",
        ),
    ];
    for (bytes, words) in bad {
        let msg = common::chain(&load_glb(&bytes).unwrap_err());
        assert!(msg.contains(words), "{msg}");
    }
}

#[test]
fn exr_images_are_read_header_first_and_only_from_regular_files() {
    use adaptive_pm::render::Image;
    let dir = tempfile::tempdir().unwrap();
    let small = dir.path().join("small.exr");
    let image = Image {
        width: 4,
        height: 3,
        pixels: (0..12).map(|i| Vec3::splat(i as f32)).collect(),
    };
    image.write_exr(&small).unwrap();
    assert_eq!(Image::read_exr(&small).unwrap(), image);
    // A 1 KB file whose header claims 30000 x 30000 pixels (10.8 GB), then
    // 16000 x 16000 (a size allowed, but not in a file this small).
    for (side, words) in [(30000, "must be in 1..=16384"), (16000, "blocks of pixels")] {
        let mut bytes = std::fs::read(&small).unwrap();
        common::claim_exr_size(&mut bytes, side);
        let big = dir.path().join("big.exr");
        std::fs::write(&big, bytes).unwrap();
        let msg = common::chain(&Image::read_exr(&big).unwrap_err());
        assert!(msg.contains(words), "{side}: {msg}");
    }
    // A FIFO is refused before it is opened (opening it would block).
    let fifo = dir.path().join("fifo.exr");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(made.success());
    let e = Image::read_exr(&fifo).unwrap_err();
    assert!(matches!(e, Error::Io { .. }), "{e}");
}
