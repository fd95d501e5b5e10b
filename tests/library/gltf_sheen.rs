//! `KHR_materials_sheen` read into the glTF BRDF: its factors reach the
//! model bit for bit, its textures multiply them where a hit lands (the
//! colour sRGB-decoded, the roughness from alpha), bad values are refused by
//! name, glass and a polished metal say they drop it, and photons reflect
//! from a sheen over a black floor.

use adaptive_pm::brdf::{Brdf, GltfPbr};
use adaptive_pm::render::RenderConfig;
use adaptive_pm::scene::Scene;
use glam::Vec3;
use serde_json::{json, Value};

use crate::common;
use crate::gltf_alpha_mask::{load, load_err, png_rgba};
use crate::gltf_doc::Doc;
use crate::gltf_layers::{brdf_at, pbr};
use crate::gltf_textures::reflected_up;

const SHEEN: &str = "KHR_materials_sheen";

/// A matte floor of grey `base` (roughness 1: Lambert without a layer)
/// under the extension object `sheen` (none when `Value::Null`), in
/// `gltf_textures`' floor scene with the ceiling that records what it
/// reflects up; the document uses the extension.
fn sheened(base: f32, sheen: Value) -> Doc {
    let mut m = json!({"name": "floor", "pbrMetallicRoughness":
        {"baseColorFactor": [base, base, base, 1.0], "metallicFactor": 0.0,
         "roughnessFactor": 1.0}});
    if !sheen.is_null() {
        m["extensions"] = json!({ SHEEN: sheen });
    }
    let mut doc = crate::gltf_textures::floor_scene(None, m, true);
    doc.extensions_used.push(SHEEN);
    doc
}

/// Sets extension `ext`'s object on the floor's material to `value`.
fn with_extension(doc: &mut Doc, ext: &'static str, value: Value) {
    doc.materials[0]["extensions"][ext] = value;
    // Named once: the validator refuses duplicates in extensionsUsed.
    if !doc.extensions_used.contains(&ext) {
        doc.extensions_used.push(ext);
    }
}

fn white(roughness: f32) -> Value {
    json!({"sheenColorFactor": [1.0, 1.0, 1.0], "sheenRoughnessFactor": roughness})
}

/// sRGB-encoded 8-bit `c`, decoded.
fn srgb(c: u8) -> f32 {
    let c = f64::from(c) / 255.0;
    let linear = if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    };
    linear as f32
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() < 1e-5
}

#[test]
fn the_factors_reach_the_model_bit_for_bit() {
    let colour = [0.9f32, 0.55, 0.125];
    let velvet = json!({"sheenColorFactor": colour, "sheenRoughnessFactor": 0.3});
    let scene = load(&sheened(0.5, velvet.clone()));
    // A sheened matte dielectric is the glTF BRDF, not Lambert.
    let (c, r) = pbr(scene.materials()[0].brdf).sheen();
    assert_eq!(c.to_array().map(f32::to_bits), colour.map(f32::to_bits));
    assert_eq!(r.to_bits(), 0.3f32.to_bits());
    let w = scene.warnings().join("\n");
    assert!(!w.contains(SHEEN), "the extension is modelled: {w}");
    // A roughness below the model's least is raised to it; absent, it is 0.
    for sheen in [white(0.02), json!({"sheenColorFactor": [1.0, 1.0, 1.0]})] {
        let g = pbr(load(&sheened(0.5, sheen)).materials()[0].brdf);
        assert_eq!(g.sheen(), (Vec3::ONE, GltfPbr::MIN_SHEEN_ROUGHNESS));
    }
    // Black, the default colour, is no sheen: the floor without the
    // extension, bit for bit.
    let none = load(&sheened(0.5, json!({"sheenRoughnessFactor": 0.5})));
    let plain = load(&sheened(0.5, Value::Null));
    assert!(matches!(none.materials()[0].brdf, Brdf::Lambert(_)));
    assert_eq!(none.materials()[0].brdf, plain.materials()[0].brdf);
    // Under a clear coat: both layers.
    let mut doc = sheened(0.5, velvet);
    with_extension(
        &mut doc,
        "KHR_materials_clearcoat",
        json!({"clearcoatFactor": 1.0}),
    );
    let g = pbr(load(&doc).materials()[0].brdf);
    assert_eq!((g.sheen().1, g.clearcoat().0), (0.3, 1.0));
}

#[test]
fn bad_factors_are_refused_by_name() {
    let colour = "sheenColorFactor";
    let roughness = "sheenRoughnessFactor";
    for (sheen, what) in [
        (json!({colour: [1.0, -0.5, 1.0]}), colour),
        (json!({colour: [1.0, 1.5, 1.0]}), colour),
        // Infinite in f32.
        (json!({colour: [1e300, 1.0, 1.0]}), colour),
        (json!({colour: [1.0, 1.0]}), colour),
        (json!({colour: [1.0, 1.0, 1.0, 1.0]}), colour),
        (json!({colour: ["red", 1.0, 1.0]}), colour),
        (json!({ colour: 0.5 }), colour),
        (json!({ roughness: 1.5 }), roughness),
        (json!({ roughness: -0.25 }), roughness),
        (json!({ roughness: 1e300 }), roughness),
        (json!({ roughness: "smooth" }), roughness),
        (json!({ roughness: null }), roughness),
        (json!(3), SHEEN),
    ] {
        let e = load_err(&sheened(0.5, sheen.clone()));
        assert!(e.contains("floor") && e.contains(what), "{sheen}: {e}");
    }
}

/// The floor under a sheen whose colour and roughness both read one 2 x 1
/// texture (nearest, clamped): the colour in RGB (sRGB), the roughness in
/// alpha (linear); left (188, 255, 51) and 255, right (255, 0, 255) and 51.
/// Factors: colour (1, 0.8, 0.5), roughness 0.8. `edit` changes the
/// extension object.
fn textured(edit: impl FnOnce(&mut Value)) -> Doc {
    let sampler = json!({"magFilter": 9728, "wrapS": 33071, "wrapT": 33071});
    let mut doc = sheened(0.5, Value::Null);
    let texels = [[188, 255, 51, 255], [255, 0, 255, 51]];
    let t = doc.texture(&png_rgba(2, 1, &texels), sampler);
    let mut sheen = json!({"sheenColorFactor": [1.0, 0.8, 0.5], "sheenColorTexture": {"index": t},
        "sheenRoughnessFactor": 0.8, "sheenRoughnessTexture": {"index": t}});
    edit(&mut sheen);
    doc.materials[0]["extensions"] = json!({ SHEEN: sheen });
    doc
}

#[test]
fn the_textures_multiply_the_factors_where_a_hit_lands() {
    let scene = load(&textured(|_| {}));
    let factor = Vec3::new(1.0, 0.8, 0.5);
    let left = factor * Vec3::new(srgb(188), 1.0, srgb(51));
    let right = factor * Vec3::new(1.0, 0.0, 1.0);
    let (c, r) = pbr(brdf_at(&scene, -1.0, 0.0)).sheen();
    assert!(close(c, left) && (r - 0.8).abs() < 1e-6, "left: {c} {r}");
    let (c, r) = pbr(brdf_at(&scene, 1.0, 0.0)).sheen();
    let right_r = 0.8 * 51.0 / 255.0;
    assert!(
        close(c, right) && (r - right_r).abs() < 1e-6,
        "right: {c} {r}"
    );
    // The material's own model, for the photon counts, is at the mean texels.
    let (c, r) = pbr(scene.materials()[0].brdf).sheen();
    assert!(close(c, (left + right) / 2.0), "mean: {c}");
    assert!((r - (0.8 + right_r) / 2.0).abs() < 1e-6, "mean: {r}");
    // Each texture reads through its own transform: half an image's offset,
    // clamped, puts the right texel under the left half.
    let mut doc = textured(|s| {
        s["sheenRoughnessTexture"]["extensions"] =
            json!({"KHR_texture_transform": {"offset": [0.5, 0.0]}});
    });
    doc.extensions_used.push("KHR_texture_transform");
    let (c, r) = pbr(brdf_at(&load(&doc), -1.0, 0.0)).sheen();
    assert!(
        close(c, left) && (r - right_r).abs() < 1e-6,
        "shifted: {c} {r}"
    );
    // ... and its own texCoord: TEXCOORD_1, which the floor lacks.
    let e = load_err(&textured(|s| s["sheenColorTexture"]["texCoord"] = json!(1)));
    assert!(e.contains("TEXCOORD_1"), "{e}");
    // A texture that does not exist, and a texture info that is not one.
    for (info, what) in [
        (json!({"index": 7}), "texture 7"),
        (
            json!({"texCoord": 0}),
            "sheenColorTexture is not a texture info",
        ),
    ] {
        let e = load_err(&textured(|s| s["sheenColorTexture"] = info));
        assert!(e.contains("floor") && e.contains(what), "{e}");
    }
}

#[test]
fn glass_and_a_polished_metal_drop_the_sheen_with_a_warning() {
    // Glass, whole or in part: the transmitting part has no sheen; the
    // opaque part of a mix keeps it.
    for t in [1.0, 0.5] {
        let mut doc = sheened(1.0, white(0.5));
        doc.materials[0]["pbrMetallicRoughness"]["roughnessFactor"] = json!(0.3);
        let transmission = json!({ "transmissionFactor": t });
        with_extension(&mut doc, "KHR_materials_transmission", transmission);
        let scene = load(&doc);
        let w = scene.warnings().join("\n");
        let warned = "KHR_materials_sheen is not modelled on its transmitting (glass) part";
        assert!(w.contains(warned), "transmission {t}: {w}");
        match scene.materials()[0].brdf {
            Brdf::GltfPbr(g) => assert_eq!(g.sheen(), (Vec3::ONE, 0.5)),
            b => assert!(matches!(b, Brdf::RoughDielectric(_)), "{b:?}"),
        }
    }
    // A black sheen on glass is none: nothing to warn of.
    let mut doc = sheened(1.0, json!({"sheenRoughnessFactor": 0.5}));
    let transmission = json!({"transmissionFactor": 1.0});
    with_extension(&mut doc, "KHR_materials_transmission", transmission);
    let w = load(&doc).warnings().join("\n");
    assert!(!w.contains(SHEEN), "{w}");
    // A polished metal stays a mirror, its sheen and its sheen's texture
    // named as dropped.
    let mut doc = sheened(0.9, Value::Null);
    let core = &mut doc.materials[0]["pbrMetallicRoughness"];
    core["metallicFactor"] = json!(1.0);
    core["roughnessFactor"] = json!(0.0);
    let sampler = json!({"magFilter": 9728});
    let t = doc.texture(&png_rgba(1, 1, &[[255, 255, 255, 255]]), sampler);
    let sheen = json!({"sheenColorFactor": [1.0, 1.0, 1.0], "sheenColorTexture": {"index": t}});
    with_extension(&mut doc, SHEEN, sheen);
    let scene = load(&doc);
    assert!(matches!(scene.materials()[0].brdf, Brdf::Mirror(_)));
    let w = scene.warnings().join("\n");
    assert!(
        w.contains("KHR_materials_sheen is not modelled on a polished metal"),
        "{w}"
    );
    assert!(w.contains("sheen textures are not read"), "{w}");
}

#[test]
fn a_file_may_require_the_extension() {
    let doc = sheened(0.5, white(0.5));
    let dir = tempfile::tempdir().unwrap();
    let path = doc.write(dir.path());
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    v["extensionsRequired"] = json!([SHEEN]);
    std::fs::write(&path, v.to_string()).unwrap();
    let scene = Scene::load(&path).unwrap();
    assert_eq!(pbr(scene.materials()[0].brdf).sheen(), (Vec3::ONE, 0.5));
}

#[test]
fn photons_reflect_from_a_sheen_over_a_black_floor() {
    // A black floor with its specular reflection off (specularFactor 0)
    // reflects nothing; under a white sheen it reflects what the sheen
    // does, and under a sheen of half that colour half of it (over a black
    // base the sheen's lobe is linear in its colour).
    let floor = |sheen: Value| {
        let mut doc = sheened(0.0, sheen);
        let off = json!({"specularFactor": 0.0});
        with_extension(&mut doc, "KHR_materials_specular", off);
        load(&doc)
    };
    let white_sheen = floor(white(0.5));
    let grey_sheen =
        floor(json!({"sheenColorFactor": [0.5, 0.5, 0.5], "sheenRoughnessFactor": 0.5}));
    let black = floor(Value::Null);
    assert!(matches!(black.materials()[0].brdf, Brdf::Lambert(_)));
    let seed = common::seed(53);
    let (w, w_se) = reflected_up(&white_sheen, seed);
    let (g, g_se) = reflected_up(&grey_sheen, seed + 1);
    let (b, b_se) = reflected_up(&black, seed + 2);
    eprintln!("reflected up: white sheen {w} +- {w_se}, grey {g} +- {g_se}, none {b} +- {b_se}");
    let se = w_se.hypot(b_se);
    assert!(
        w - b > common::MIN_SIGMAS * se,
        "the sheen reflects: {w} vs {b} (se {se})"
    );
    let se = g_se.hypot(0.5 * w_se);
    common::assert_within_noise(
        "half the colour, half the light",
        g - 0.5 * w,
        se,
        common::MIN_SIGMAS * se,
    );
}

/// `assets/velvet.gltf` (`tools/make_velvet.py`): a carpet, red and black
/// velvet spheres and a lacquered cushion under a sheen, read as written,
/// and its photon render agrees with the path tracer within their measured
/// noise (the photons scatter by the sampler and its weights, the path
/// tracer's camera paths by the same model seen from the other side). The
/// render reads the map's k nearest photons, each weighted by the BRDF: the
/// irradiance cache reads a sheen as a diffuse surface of its albedo, which
/// sits +0.8 % high on this scene's mean whatever the photon count
/// (docs/scenes.md), and this test is about the photons.
#[test]
fn the_velvet_scene_renders_as_the_path_tracer_sees_it() {
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/velvet.gltf");
    let scene = Scene::load(file).unwrap();
    assert!(scene.warnings().is_empty(), "{:?}", scene.warnings());
    let sheen_of = |name: &str| {
        let m = scene.materials().iter().find(|m| m.name == name).unwrap();
        pbr(m.brdf).sheen()
    };
    assert_eq!(sheen_of("red_velvet"), (Vec3::new(1.0, 0.35, 0.45), 0.3));
    assert_eq!(sheen_of("black_velvet"), (Vec3::splat(0.9), 0.5));
    let cushion = scene
        .materials()
        .iter()
        .find(|m| m.name == "lacquered_cushion");
    assert_eq!(pbr(cushion.unwrap().brdf).clearcoat().0, 0.5);
    let mut cfg = RenderConfig::new(32, 32);
    cfg.cache_stride = 0;
    crate::partial_transmission::assert_renders_agree_with("the velvet scene", &scene, cfg, 83);
}
