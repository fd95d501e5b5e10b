//! Textured glTF materials: the texel under a hit sets the BRDF there
//! (base colour sRGB-decoded, through the sampler and the texture
//! transform), photons reflect by it, and bad texture data is refused by
//! name. Scenes are small JSON files with their geometry and PNG images in
//! a `data:` buffer.

use adaptive_pm::brdf::Brdf;
use adaptive_pm::embree::Device;
use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
use adaptive_pm::raycast::Ray;
use adaptive_pm::scene::{flat_base_color, Scene};
use glam::Vec3;
use serde_json::{json, Value};
use std::sync::Arc;

use crate::common;
use crate::gltf_doc::{square, Doc};

const NEAREST_CLAMP: &str = r#"{"magFilter": 9728, "wrapS": 33071, "wrapT": 33071}"#;
const NEAREST_REPEAT: &str = r#"{"magFilter": 9728}"#;

/// An 8-bit RGB PNG of `w x h` pixels.
pub(crate) fn png_rgb(w: u32, h: u32, rgb: &[[u8; 3]]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, w, h);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let data: Vec<u8> = rgb.iter().flatten().copied().collect();
    enc.write_header().unwrap().write_image_data(&data).unwrap();
    out
}

/// red, green / blue, white
fn four_colours() -> Vec<u8> {
    png_rgb(
        2,
        2,
        &[[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 255]],
    )
}

/// A 4 x 4 floor facing up at y = 0, its texture coordinates (0, 0) at
/// (-2, -2) and (1, 1) at (2, 2); a lamp of half-size 0.5 facing down at
/// y = 1; and, when `ceiling`, a black ceiling facing down at y = 1.5 that
/// records the photons the floor reflects up. `floor` is the floor's
/// material JSON; the texture, when given, is texture 0.
pub(crate) fn floor_scene(texture: Option<(&[u8], &str)>, floor: Value, ceiling: bool) -> Doc {
    let mut doc = Doc::default();
    if let Some((png, sampler)) = texture {
        doc.texture(png, serde_json::from_str(sampler).unwrap());
    }
    let floor_m = doc.material(floor);
    let lamp = doc.material(json!({"name": "lamp", "emissiveFactor": [1.0, 1.0, 1.0],
        "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0}}));
    let (p, i) = square(2.0, true);
    let f = doc.mesh(&p, &i, 4, Some(floor_m));
    doc.texcoords(f, &[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
    doc.node(json!({ "mesh": f }));
    let (p, i) = square(0.5, false);
    let l = doc.mesh(&p, &i, 4, Some(lamp));
    doc.node(json!({"mesh": l, "translation": [0.0, 1.0, 0.0]}));
    if ceiling {
        let black = doc.material(json!({"name": "black",
            "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0}}));
        let (p, i) = square(2.0, false);
        let c = doc.mesh(&p, &i, 4, Some(black));
        doc.node(json!({"mesh": c, "translation": [0.0, 1.5, 0.0]}));
    }
    doc
}

fn matte(base: f32, texture: Option<Value>) -> Value {
    let mut m = json!({"name": "floor", "pbrMetallicRoughness":
        {"baseColorFactor": [base, base, base, 1.0], "metallicFactor": 0.0}});
    if let Some(t) = texture {
        m["pbrMetallicRoughness"]["baseColorTexture"] = t;
    }
    m
}

fn load(doc: &Doc) -> Scene {
    let dir = tempfile::tempdir().unwrap();
    Scene::load(doc.write(dir.path())).unwrap()
}

fn load_err(doc: &Doc) -> String {
    let dir = tempfile::tempdir().unwrap();
    Scene::load(doc.write(dir.path())).unwrap_err().to_string()
}

/// The Lambert albedo at the floor point above which a ray at (x, 1, z)
/// straight down lands.
fn albedo_at(scene: &Scene, x: f32, z: f32) -> Vec3 {
    let device = Device::new().unwrap();
    let committed = scene.clone().commit(&device).unwrap();
    let ray = Ray::new(Vec3::new(x, 0.5, z), Vec3::NEG_Y);
    let hit = committed
        .caster()
        .intersect(&ray)
        .expect("the floor is below");
    match scene.surface_brdf(&hit) {
        Some(Brdf::Lambert(l)) => l.albedo,
        other => panic!("a matte floor is Lambert, got {other:?}"),
    }
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() < 1e-6
}

#[test]
fn the_texel_under_a_hit_sets_the_base_colour() {
    let tex = json!({"index": 0});
    let doc = floor_scene(
        Some((&four_colours(), NEAREST_CLAMP)),
        matte(1.0, Some(tex)),
        false,
    );
    let scene = load(&doc);
    assert!(close(albedo_at(&scene, -1.0, -1.0), Vec3::X), "red");
    assert!(close(albedo_at(&scene, 1.0, -1.0), Vec3::Y), "green");
    assert!(close(albedo_at(&scene, -1.0, 1.0), Vec3::Z), "blue");
    assert!(close(albedo_at(&scene, 1.0, 1.0), Vec3::ONE), "white");
    // The material's own BRDF is the texels' mean, for the photon counts.
    let m = &scene.materials()[scene.meshes()[0].material];
    assert!(matches!(m.brdf, Brdf::Lambert(l) if close(l.albedo, Vec3::splat(0.5))));
    let maps = scene.material_maps(scene.meshes()[0].material).unwrap();
    assert!(close(flat_base_color(&scene, maps), Vec3::splat(0.5)));
}

#[test]
fn srgb_texels_are_decoded_and_factors_multiply_them() {
    // sRGB 188 is linear 0.5029; the factor 0.5 halves it.
    let png = png_rgb(1, 1, &[[188, 188, 188]]);
    let doc = floor_scene(
        Some((&png, NEAREST_CLAMP)),
        matte(0.5, Some(json!({"index": 0}))),
        false,
    );
    let want = 0.5 * ((188.0f32 / 255.0 + 0.055) / 1.055).powf(2.4);
    let got = albedo_at(&load(&doc), 0.3, 0.7);
    assert!(
        (got - Vec3::splat(want)).abs().max_element() < 1e-5,
        "{got} vs {want}"
    );
}

#[test]
fn the_texture_transform_moves_the_lookup() {
    // Offset by half the image along u, with REPEAT: red's place reads green.
    let tex = json!({"index": 0, "extensions": {"KHR_texture_transform": {"offset": [0.5, 0.0]}}});
    let mut doc = floor_scene(
        Some((&four_colours(), NEAREST_REPEAT)),
        matte(1.0, Some(tex)),
        false,
    );
    doc.extensions_used.push("KHR_texture_transform");
    let scene = load(&doc);
    assert!(close(albedo_at(&scene, -1.0, -1.0), Vec3::Y));
    assert!(close(albedo_at(&scene, 1.0, -1.0), Vec3::X));
    // A scale of 2 tiles the image twice: (-1, -1) is uv (0.5, 0.5), white.
    let tex = json!({"index": 0, "extensions": {"KHR_texture_transform": {"scale": [2.0, 2.0]}}});
    let mut doc = floor_scene(
        Some((&four_colours(), NEAREST_REPEAT)),
        matte(1.0, Some(tex)),
        false,
    );
    doc.extensions_used.push("KHR_texture_transform");
    assert!(close(albedo_at(&load(&doc), -0.9, -0.9), Vec3::ONE));
}

/// Power the floor reflects onto the ceiling (photons stored there at
/// depth 1), and its standard error from the photons' own spread.
pub(crate) fn reflected_up(scene: &Scene, seed: u64) -> (f64, f64) {
    let device = Device::new().unwrap();
    let tracer = Tracer::new(Arc::new(scene.clone().commit(&device).unwrap()));
    let mut cfg = TraceConfig::new(Mode::Classic, Budget::NMax(300_000));
    cfg.seed = seed;
    let out = tracer.trace(&cfg).unwrap();
    let powers: Vec<f64> = out
        .records()
        .iter()
        .filter(|r| r.depth == 1 && (r.position.y - 1.5).abs() < 1e-3)
        .map(|r| f64::from(r.power.x))
        .collect();
    let sum: f64 = powers.iter().sum();
    // A sum of independent photons: its variance is the sum of squares.
    let var: f64 = powers.iter().map(|p| p * p).sum();
    (sum, var.sqrt())
}

#[test]
fn a_textured_floor_reflects_like_its_mean_as_a_flat_factor() {
    // A black and white checker, 32 x 32 squares over the floor, factor 0.8:
    // it reflects like a flat 0.4, and half what the factor alone would.
    let checker = png_rgb(
        2,
        2,
        &[[255, 255, 255], [0, 0, 0], [0, 0, 0], [255, 255, 255]],
    );
    let tex = json!({"index": 0, "extensions": {"KHR_texture_transform": {"scale": [16.0, 16.0]}}});
    let mut doc = floor_scene(
        Some((&checker, NEAREST_REPEAT)),
        matte(0.8, Some(tex)),
        true,
    );
    doc.extensions_used.push("KHR_texture_transform");
    let textured = load(&doc);
    let maps = textured.material_maps(0).unwrap();
    let mean = flat_base_color(&textured, maps).x;
    assert!((mean - 0.4).abs() < 1e-6, "{mean}");
    let flat = load(&floor_scene(None, matte(mean, None), true));
    let factor_only = load(&floor_scene(None, matte(0.8, None), true));
    let seed = common::seed(41);
    let (t, t_se) = reflected_up(&textured, seed);
    let (f, f_se) = reflected_up(&flat, seed + 1);
    let (o, o_se) = reflected_up(&factor_only, seed + 2);
    eprintln!(
        "reflected up: textured {t} +- {t_se}, flat {f} +- {f_se}, factor alone {o} +- {o_se}"
    );
    let se = t_se.hypot(f_se);
    common::assert_within_noise("textured vs flat mean", t - f, se, 4.0 * se);
    // The texture is read: half of the factor alone, far outside the noise.
    let half_se = (0.5 * o_se).hypot(t_se);
    common::assert_within_noise(
        "textured vs half the factor",
        t - 0.5 * o,
        half_se,
        4.0 * half_se,
    );
}

#[test]
fn bad_texture_data_is_refused_by_name() {
    let tex = |t: Value| {
        floor_scene(
            Some((&four_colours(), NEAREST_CLAMP)),
            matte(1.0, Some(t)),
            false,
        )
    };
    let e = load_err(&tex(json!({"index": 3})));
    assert!(e.contains("refers to texture 3"), "{e}");
    let e = load_err(&tex(json!({"index": 0, "texCoord": 40})));
    assert!(e.contains("TEXCOORD_40"), "{e}");
    let e = load_err(&tex(json!({"index": 0, "texCoord": 1})));
    assert!(e.contains("no TEXCOORD_1"), "{e}");
    let mut broken = four_colours();
    broken.truncate(30);
    let doc = floor_scene(
        Some((&broken, NEAREST_CLAMP)),
        matte(1.0, Some(json!({"index": 0}))),
        false,
    );
    let e = load_err(&doc);
    assert!(e.contains("image 0") && e.contains("PNG"), "{e}");
    let mut doc = floor_scene(
        Some((&four_colours(), NEAREST_CLAMP)),
        matte(1.0, Some(json!({"index": 0}))),
        false,
    );
    doc.samplers[0]["wrapS"] = json!(1234);
    assert!(load_err(&doc).contains("wrap mode"));
    // Signed bytes as texture coordinates (the gltf crate's reader would
    // reach `unreachable!`) in a file without KHR_mesh_quantization, which
    // allows them: refused naming the extension, not a panic.
    let mut doc = floor_scene(
        Some((&four_colours(), NEAREST_CLAMP)),
        matte(1.0, Some(json!({"index": 0}))),
        false,
    );
    let uv = doc.meshes[0]["primitives"][0]["attributes"]["TEXCOORD_0"]
        .as_u64()
        .unwrap() as usize;
    doc.accessors[uv]["componentType"] = json!(5120);
    doc.accessors[uv]["normalized"] = json!(true);
    let e = load_err(&doc);
    assert!(
        e.contains("TEXCOORD_0") && e.contains("needs the extension KHR_mesh_quantization"),
        "{e}"
    );
}

#[test]
fn what_is_not_modelled_is_a_warning() {
    let mut m = matte(1.0, Some(json!({"index": 0})));
    m["emissiveTexture"] = json!({"index": 0});
    m["normalTexture"] = json!({"index": 0});
    // MASK is modelled (gltf_alpha_mask.rs); BLEND is traced as opaque.
    m["alphaMode"] = json!("BLEND");
    let scene = load(&floor_scene(
        Some((&four_colours(), NEAREST_CLAMP)),
        m,
        false,
    ));
    let w = scene.warnings().join("\n");
    assert!(w.contains("alphaMode BLEND"), "{w}");
    // Emission and normal textures are modelled now: no warning names them.
    assert!(
        !w.contains("normalTexture") && !w.contains("not modelled: its emissive"),
        "{w}"
    );
}

#[test]
fn an_image_file_beside_the_scene_is_read_and_one_outside_is_not() {
    let doc = floor_scene(
        Some((&four_colours(), NEAREST_CLAMP)),
        matte(1.0, Some(json!({"index": 0}))),
        false,
    );
    let dir = tempfile::tempdir().unwrap();
    let scene_dir = dir.path().join("scene");
    std::fs::create_dir(&scene_dir).unwrap();
    let path = doc.write(&scene_dir);
    let with_uri = |uri: &str| {
        let mut v: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        v["images"][0] = json!({ "uri": uri });
        std::fs::write(&path, v.to_string()).unwrap();
    };
    std::fs::write(scene_dir.join("four colours.png"), four_colours()).unwrap();
    with_uri("four%20colours.png");
    let scene = Scene::load(&path).unwrap();
    assert!(close(albedo_at(&scene, 1.0, -1.0), Vec3::Y));
    std::fs::write(dir.path().join("outside.png"), four_colours()).unwrap();
    with_uri("../outside.png");
    let e = Scene::load(&path).unwrap_err().to_string();
    assert!(e.contains("image 0") && e.contains("folder"), "{e}");
}

#[test]
fn a_texture_without_an_image_leaves_the_factors_and_a_warning() {
    // glTF lets a texture leave `source` out when an extension (WebP,
    // Basis Universal) gives its image; such images are not decoded, so
    // every map reading it falls back to its factor, with a warning.
    let mut m = matte(0.7, Some(json!({"index": 0})));
    m["emissiveTexture"] = json!({"index": 0});
    m["emissiveFactor"] = json!([0.0, 0.0, 0.0]);
    m["normalTexture"] = json!({"index": 0});
    m["alphaMode"] = json!("MASK");
    let mut doc = floor_scene(Some((&four_colours(), NEAREST_CLAMP)), m, false);
    doc.textures[0]
        .as_object_mut()
        .unwrap()
        .remove("source")
        .expect("the texture had a source");
    let scene = load(&doc);
    assert!(close(albedo_at(&scene, -1.0, -1.0), Vec3::splat(0.7)));
    assert!(close(albedo_at(&scene, 1.0, 1.0), Vec3::splat(0.7)));
    let w = scene.warnings().join("\n");
    assert_eq!(w.matches("has no `source` image").count(), 1, "{w}");
    assert!(w.contains("texture 0"), "{w}");
    // It traces: the floor reflects its factor.
    let tracer = Tracer::new(scene.commit(&Device::new().unwrap()).unwrap());
    let run = tracer
        .trace(&TraceConfig::new(Mode::Classic, Budget::NMax(2000)))
        .unwrap();
    assert!(run.report.stored > 0);
}

#[test]
fn vertex_colours_multiply_the_base_colour_where_a_hit_lands() {
    let corners = [
        [255, 0, 0, 255],
        [0, 255, 0, 255],
        [0, 0, 255, 255],
        [255, 255, 255, 0],
    ];
    let mut doc = floor_scene(None, matte(0.5, None), false);
    doc.colors(0, &corners);
    let scene = load(&doc);
    let near = |x: f32, z: f32, want: Vec3| {
        let a = albedo_at(&scene, x, z);
        assert!(
            (a - want).abs().max_element() < 0.01,
            "at ({x}, {z}): {a}, want {want}"
        );
    };
    // Vertex 0 at (-2, -2) is red, 1 at (2, -2) green, 2 at (2, 2) blue,
    // 3 at (-2, 2) white (its alpha is not read); the factor halves each.
    near(-1.999, -1.999, Vec3::new(0.5, 0.0, 0.0));
    near(1.999, -1.999, Vec3::new(0.0, 0.5, 0.0));
    near(1.999, 1.999, Vec3::new(0.0, 0.0, 0.5));
    near(-1.999, 1.999, Vec3::splat(0.5));
    // The diagonal (0 to 2) is shared by both triangles: the mean of its ends.
    near(0.0, 0.0, Vec3::new(0.25, 0.0, 0.25));
    assert!(!scene.warnings().join(" ").contains("COLOR_0"));
    // A colour outside [0, 1] (a float accessor) is refused by name.
    let mut doc = floor_scene(None, matte(0.5, None), false);
    doc.colors(0, &corners);
    let last = doc.accessors.len() - 1;
    doc.accessors[last]["normalized"] = json!(false);
    let e = load_err(&doc);
    assert!(e.contains("vertex colour") && e.contains("[0, 1]"), "{e}");
}

#[test]
fn a_floor_of_grey_vertex_colours_reflects_like_the_flat_product() {
    // Every vertex 128/255 grey, factor 0.8: it reflects like a flat
    // 0.8 * 128/255, about half what the factor alone would.
    let grey = 128.0 / 255.0;
    let mut doc = floor_scene(None, matte(0.8, None), true);
    doc.colors(0, &[[128, 128, 128, 255]; 4]);
    let coloured = load(&doc);
    let flat = load(&floor_scene(None, matte(0.8 * grey, None), true));
    let factor_only = load(&floor_scene(None, matte(0.8, None), true));
    let seed = common::seed(43);
    let (c, c_se) = reflected_up(&coloured, seed);
    let (f, f_se) = reflected_up(&flat, seed + 1);
    let (o, o_se) = reflected_up(&factor_only, seed + 2);
    eprintln!("reflected up: coloured {c} +- {c_se}, flat {f} +- {f_se}, factor {o} +- {o_se}");
    let se = c_se.hypot(f_se);
    common::assert_within_noise("coloured vs flat product", c - f, se, 4.0 * se);
    let scaled_se = (grey as f64 * o_se).hypot(c_se);
    common::assert_within_noise(
        "coloured vs the scaled factor",
        c - grey as f64 * o,
        scaled_se,
        4.0 * scaled_se,
    );
    assert!(
        o - c > 10.0 * o_se.hypot(c_se),
        "the colours are read: {o} vs {c}"
    );
}

/// A partly transmitting floor (`KHR_materials_transmission` 0.5): the
/// base colour texel colours its opaque part, the glass part takes the
/// factors; on a transmitting partial metal a metallic-roughness texture
/// is refused (the glass share would vary by texel).
#[test]
fn textures_colour_the_opaque_part_of_a_partly_transmitting_surface() {
    let partly = |pbr: Value| {
        json!({"name": "floor", "pbrMetallicRoughness": pbr,
            "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.5}}})
    };
    let pbr = json!({"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0,
        "roughnessFactor": 1.0, "baseColorTexture": {"index": 0}});
    let mut doc = floor_scene(Some((&four_colours(), NEAREST_CLAMP)), partly(pbr), false);
    doc.extensions_used.push("KHR_materials_transmission");
    let scene = load(&doc);
    assert!(close(albedo_at(&scene, -1.0, -1.0), Vec3::X), "red");
    assert!(close(albedo_at(&scene, 1.0, 1.0), Vec3::ONE), "white");
    let floor = scene.meshes()[0].material;
    let mix = scene.transmission_mix(floor as u32).unwrap();
    assert_eq!(mix.weight, 0.5);
    let Brdf::RoughDielectric(glass) = scene.materials()[mix.glass].brdf else {
        panic!("roughness 1: rough glass")
    };
    assert_eq!(glass.tint(), Vec3::ONE, "the factor's tint");

    let metal = json!({"metallicFactor": 0.5, "roughnessFactor": 1.0,
        "metallicRoughnessTexture": {"index": 0}});
    let mut doc = floor_scene(Some((&four_colours(), NEAREST_CLAMP)), partly(metal), false);
    doc.extensions_used.push("KHR_materials_transmission");
    let e = load_err(&doc);
    assert!(
        e.contains(
            "transmitting partial metal (metallicFactor 0.5) with a metallicRoughnessTexture"
        ),
        "{e}"
    );
}

/// `four_colours` as a lossless WebP (VP8L), written by Pillow 12
/// (`Image.save(..., 'WEBP', lossless=True)`).
const FOUR_COLOURS_WEBP: [u8; 52] = [
    82, 73, 70, 70, 44, 0, 0, 0, 87, 69, 66, 80, 86, 80, 56, 76, 31, 0, 0, 0, 47, 1, 64, 0, 0, 31,
    32, 16, 72, 222, 31, 58, 141, 249, 23, 16, 20, 252, 31, 221, 252, 71, 100, 15, 224, 6, 12, 17,
    253, 15, 1, 0,
];

/// An 8 x 8 image of sRGB grey 188 as a lossy WebP (VP8, quality 90, by
/// Pillow 12), which decodes to 189 (libwebp's decoder, through Pillow).
const GREY_188_LOSSY_WEBP: [u8; 44] = [
    82, 73, 70, 70, 36, 0, 0, 0, 87, 69, 66, 80, 86, 80, 56, 32, 24, 0, 0, 0, 48, 1, 0, 157, 1, 42,
    8, 0, 8, 0, 0, 192, 18, 37, 164, 0, 3, 112, 0, 254, 250, 204, 128, 0,
];

/// `EXT_texture_webp` with no `source`: the WebP image colours the floor
/// as the PNG does (lossless: the same texels), and a lossy one within
/// its rounding.
#[test]
fn a_webp_image_colours_the_floor() {
    let mut doc = floor_scene(None, matte(1.0, Some(json!({"index": 0}))), false);
    doc.webp_texture(
        &FOUR_COLOURS_WEBP,
        serde_json::from_str(NEAREST_CLAMP).unwrap(),
        None,
    );
    let scene = load(&doc);
    assert!(scene.warnings().is_empty(), "{:?}", scene.warnings());
    assert!(close(albedo_at(&scene, -1.0, -1.0), Vec3::X), "red");
    assert!(close(albedo_at(&scene, 1.0, -1.0), Vec3::Y), "green");
    assert!(close(albedo_at(&scene, -1.0, 1.0), Vec3::Z), "blue");
    assert!(close(albedo_at(&scene, 1.0, 1.0), Vec3::ONE), "white");

    let mut doc = floor_scene(None, matte(1.0, Some(json!({"index": 0}))), false);
    doc.webp_texture(
        &GREY_188_LOSSY_WEBP,
        serde_json::from_str(NEAREST_CLAMP).unwrap(),
        None,
    );
    let a = albedo_at(&load(&doc), 0.3, -0.7);
    // sRGB 188 and 189 are linear 0.5029 and 0.5089.
    assert!((a - Vec3::splat(0.5059)).abs().max_element() < 0.01, "{a}");
}

/// With a PNG `source` beside the WebP, the PNG is read (the same picture
/// in glTF's own format); a WebP that does not decode is refused by name.
#[test]
fn a_webp_texture_prefers_its_png_source_and_a_broken_webp_is_refused() {
    let mut doc = floor_scene(None, matte(1.0, Some(json!({"index": 0}))), false);
    let sampler = serde_json::from_str(NEAREST_CLAMP).unwrap();
    doc.webp_texture(&GREY_188_LOSSY_WEBP, sampler, Some(&four_colours()));
    assert!(
        close(albedo_at(&load(&doc), -1.0, -1.0), Vec3::X),
        "the PNG's red"
    );

    // Cut short: its chunks declare more bytes than there are.
    let broken = &FOUR_COLOURS_WEBP[..40];
    let mut doc = floor_scene(None, matte(1.0, Some(json!({"index": 0}))), false);
    doc.webp_texture(broken, serde_json::from_str(NEAREST_CLAMP).unwrap(), None);
    let e = load_err(&doc);
    assert!(e.contains("image 0") && e.contains("WebP"), "{e}");
}
