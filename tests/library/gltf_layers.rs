//! The layers of a glTF material over its base: `KHR_materials_specular`
//! (the dielectric's Fresnel term coloured and scaled as the extension
//! defines it, its textures read at each hit) and `KHR_materials_clearcoat`
//! (a clear coat of its factors); the factors checked by name, photons
//! reflected as the model says, and Blender's exported values read as
//! Blender means them.

use adaptive_pm::brdf::{Brdf, GltfPbr};
use adaptive_pm::embree::Device;
use adaptive_pm::raycast::Ray;
use adaptive_pm::scene::Scene;
use glam::Vec3;
use serde_json::{json, Value};

use crate::common;
use crate::gltf_alpha_mask::{load, load_err, png_rgba};
use crate::gltf_doc::Doc;
use crate::gltf_textures::reflected_up;

const EXT: &str = "KHR_materials_specular";

/// The floor of `gltf_textures`' scenes in material `floor`, its lamp, and
/// the black ceiling that records what the floor reflects up; the document
/// uses `KHR_materials_specular`.
fn floor_scene(floor: Value) -> Doc {
    let mut doc = crate::gltf_textures::floor_scene(None, floor, true);
    doc.extensions_used.push(EXT);
    doc
}

/// A grey dielectric of `roughness` with the extension object `specular`
/// (none when `Value::Null`).
fn floor(base: f32, roughness: f32, specular: Value) -> Value {
    let mut m = json!({"name": "floor", "pbrMetallicRoughness":
        {"baseColorFactor": [base, base, base, 1.0], "metallicFactor": 0.0,
         "roughnessFactor": roughness}});
    if !specular.is_null() {
        m["extensions"] = json!({ EXT: specular });
    }
    m
}

/// The BRDF at the floor point straight below (x, z).
pub(crate) fn brdf_at(scene: &Scene, x: f32, z: f32) -> Brdf {
    let device = Device::new().unwrap();
    let committed = scene.clone().commit(&device).unwrap();
    let ray = Ray::new(Vec3::new(x, 0.5, z), Vec3::NEG_Y);
    let hit = committed.caster().intersect(&ray).expect("the floor");
    scene.surface_brdf(&hit).unwrap()
}

pub(crate) fn pbr(b: Brdf) -> GltfPbr {
    match b {
        Brdf::GltfPbr(g) => g,
        other => panic!("a rough dielectric is the glTF BRDF, got {other:?}"),
    }
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() < 1e-6
}

#[test]
fn the_factors_colour_and_scale_the_dielectrics_fresnel_term() {
    // f0_d = min(0.04 c, 1) s and f90_d = s.
    let spec = json!({"specularFactor": 0.5, "specularColorFactor": [2.0, 1.0, 0.25]});
    let scene = load(&floor_scene(floor(0.5, 0.5, spec)));
    let g = pbr(scene.materials()[0].brdf);
    assert!(
        close(g.dielectric_f0(), Vec3::new(0.04, 0.02, 0.005)),
        "{}",
        g.dielectric_f0()
    );
    assert_eq!(g.dielectric_f90(), 0.5);
    // A colour above 1/f0 reaches the clamp: f0_d = s.
    let spec = json!({"specularFactor": 0.7, "specularColorFactor": [30.0, 30.0, 30.0]});
    let g = pbr(load(&floor_scene(floor(0.5, 0.5, spec))).materials()[0].brdf);
    assert!(close(g.dielectric_f0(), Vec3::splat(0.7)));
    // The extension at its defaults is the material without it, bit for bit
    // (Blender writes it so on glass).
    let defaults = json!({"specularFactor": 1.0, "specularColorFactor": [1.0, 1.0, 1.0]});
    let with = load(&floor_scene(floor(0.5, 0.5, defaults)));
    let without = load(&floor_scene(floor(0.5, 0.5, Value::Null)));
    assert_eq!(with.materials()[0].brdf, without.materials()[0].brdf);
    let w = with.warnings().join("\n");
    assert!(!w.contains(EXT), "the extension is modelled: {w}");
}

#[test]
fn a_specular_factor_of_zero_leaves_the_base_alone() {
    // No dielectric reflection: a rough floor is Lambert, and a glossy one
    // reflects its base colour at every angle.
    let off = json!({"specularFactor": 0.0});
    let rough = load(&floor_scene(floor(0.6, 1.0, off.clone())));
    assert!(
        matches!(rough.materials()[0].brdf, Brdf::Lambert(l) if close(l.albedo, Vec3::splat(0.6)))
    );
    let glossy = pbr(load(&floor_scene(floor(0.6, 0.3, off))).materials()[0].brdf);
    for cos in [1.0f32, 0.5, 0.1] {
        let wi = Vec3::new((1.0 - cos * cos).sqrt(), 0.0, cos);
        assert!(close(glossy.albedo(wi), Vec3::splat(0.6)), "cos {cos}");
    }
}

#[test]
fn photons_reflect_by_the_specular_factors() {
    // A glossy floor with its specular reflection off reflects exactly like
    // a Lambert floor of its base colour (its albedo is the base colour at
    // every angle), and differently from the same floor without the
    // extension, which loses light into its sheen's masking and its base's
    // coupling.
    let off = load(&floor_scene(floor(
        0.6,
        0.3,
        json!({"specularFactor": 0.0}),
    )));
    let lambert = load(&floor_scene(floor(0.6, 1.0, Value::Null)));
    assert!(matches!(lambert.materials()[0].brdf, Brdf::Lambert(_)));
    let plain = load(&floor_scene(floor(0.6, 0.3, Value::Null)));
    let seed = common::seed(77);
    let (o, o_se) = reflected_up(&off, seed);
    let (l, l_se) = reflected_up(&lambert, seed + 1);
    let (p, p_se) = reflected_up(&plain, seed + 2);
    eprintln!(
        "reflected up: specular off {o} +- {o_se}, Lambert {l} +- {l_se}, plain {p} +- {p_se}"
    );
    let se = o_se.hypot(l_se);
    common::assert_within_noise("specular off vs Lambert", o - l, se, 4.0 * se);
    let se = o_se.hypot(p_se);
    assert!(
        (o - p).abs() > 4.0 * se,
        "the extension changes what the floor reflects: {o} vs {p} (se {se})"
    );
}

#[test]
fn the_textures_multiply_the_factors_where_a_hit_lands() {
    const NEAREST_CLAMP: &str = r#"{"magFilter": 9728, "wrapS": 33071, "wrapT": 33071}"#;
    let sampler: Value = serde_json::from_str(NEAREST_CLAMP).unwrap();
    let mut doc = floor_scene(floor(0.5, 0.5, Value::Null));
    // Strength in alpha (linear): 255 on the left half, 51 (0.2) on the
    // right; colour (sRGB): 188 (linear 0.5029) in red on the left, white
    // on the right.
    let strength = doc.texture(
        &png_rgba(2, 1, &[[0, 0, 0, 255], [0, 0, 0, 51]]),
        sampler.clone(),
    );
    let colour = doc.texture(
        &png_rgba(2, 1, &[[188, 255, 255, 255], [255, 255, 255, 255]]),
        sampler,
    );
    doc.materials[0]["extensions"] = json!({EXT: {
        "specularFactor": 0.5, "specularTexture": {"index": strength},
        "specularColorFactor": [2.0, 2.0, 2.0], "specularColorTexture": {"index": colour}}});
    let scene = load(&doc);
    let srgb_188 = 0.502_886_5;
    let left = pbr(brdf_at(&scene, -1.0, 0.0));
    let want = Vec3::new(0.08 * srgb_188, 0.08, 0.08) * 0.5;
    assert!(
        (left.dielectric_f0() - want).abs().max_element() < 1e-5,
        "left: {} vs {want}",
        left.dielectric_f0()
    );
    assert_eq!(left.dielectric_f90(), 0.5);
    let right = pbr(brdf_at(&scene, 1.0, 0.0));
    let s = 0.5 * 51.0 / 255.0;
    assert!(close(right.dielectric_f0(), Vec3::splat(0.08 * s)));
    assert!((right.dielectric_f90() - s).abs() < 1e-6);
    // The material's own model, for the photon counts, is at the mean texels.
    let mean = pbr(scene.materials()[0].brdf);
    let s_mean = 0.5 * (1.0 + 0.2) / 2.0;
    assert!((mean.dielectric_f90() - s_mean).abs() < 1e-6);
}

#[test]
fn bad_factors_are_refused_by_name_and_glass_says_what_it_ignores() {
    let doc = floor_scene(floor(0.5, 0.5, json!({"specularFactor": 1.5})));
    let e = load_err(&doc);
    assert!(e.contains("floor") && e.contains("specularFactor"), "{e}");
    let doc = floor_scene(floor(
        0.5,
        0.5,
        json!({"specularColorFactor": [1.0, -0.5, 1.0]}),
    ));
    let e = load_err(&doc);
    assert!(
        e.contains("floor") && e.contains("specularColorFactor"),
        "{e}"
    );
    // Glass keeps its IOR's Fresnel term: a specular change is a warning.
    let glass = |spec: Value| {
        let mut m = floor(1.0, 0.0, spec);
        m["extensions"]["KHR_materials_transmission"] = json!({"transmissionFactor": 1.0});
        let mut doc = floor_scene(m);
        doc.extensions_used.push("KHR_materials_transmission");
        load(&doc).warnings().join("\n")
    };
    let w = glass(json!({"specularFactor": 0.3}));
    assert!(w.contains(EXT) && w.contains("glass"), "{w}");
    let w = glass(json!({"specularColorFactor": [1.0, 1.0, 1.0]}));
    assert!(!w.contains(EXT), "{w}");
}

/// `assets/blender_layers.glb`, written by Blender 3.4's exporter
/// (`tools/blender_layers.py`): Principled Specular `s` and Specular Tint
/// `t` on a base colour `b` become the dielectric reflectance Blender itself
/// uses, `0.08 s ((1 - t) + t b / lum(b))`, whatever the IOR the exporter
/// divides by and the extension multiplies back.
#[test]
fn blenders_specular_and_clearcoat_reach_the_model_as_blender_means_them() {
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/blender_layers.glb");
    let scene = Scene::load(&file).unwrap();
    let material = |name: &str| {
        let m = scene.materials().iter().find(|m| m.name == name);
        m.unwrap_or_else(|| panic!("no material {name}")).brdf
    };
    let blender_f0 = |s: f32, t: f32, b: Vec3| {
        let lum = 0.3 * b.x + 0.6 * b.y + 0.1 * b.z;
        0.08 * s * (Vec3::splat(1.0 - t) + t * b / lum)
    };
    let cases = [
        ("floor", blender_f0(0.25, 0.0, Vec3::splat(0.6))),
        ("tinted", blender_f0(1.0, 0.5, Vec3::new(0.8, 0.3, 0.1))),
        ("plain", Vec3::splat(0.04)),
    ];
    for (name, want) in cases {
        let g = pbr(material(name));
        let got = g.dielectric_f0();
        assert!(
            (got - want).abs().max_element() < 1e-6,
            "{name}: {got} vs {want}"
        );
        assert_eq!(g.dielectric_f90(), 1.0, "{name}");
    }
    // Specular 0 is a black specular colour: a rough base alone, Lambert.
    assert!(matches!(material("matte"), Brdf::Lambert(l) if close(l.albedo, Vec3::splat(0.5))));
    // Clearcoat 1 and Clearcoat Roughness 0.1: a coat of weight 1, alpha 0.01.
    let (w, a) = pbr(material("lacquer")).clearcoat();
    assert_eq!(w, 1.0);
    assert!((a - 0.01).abs() < 1e-7, "{a}");
    let w = scene.warnings().join("\n");
    assert!(!w.contains(EXT) && !w.contains(COAT), "{w}");
}

const COAT: &str = "KHR_materials_clearcoat";

#[test]
fn a_clear_coat_is_read_from_its_factors_and_textures() {
    let coated = |coat: Value| {
        let mut m = floor(0.5, 1.0, Value::Null);
        m["extensions"] = json!({ COAT: coat });
        let mut doc = floor_scene(m);
        doc.extensions_used.push(COAT);
        doc
    };
    // A rough matte floor under a coat is no longer Lambert.
    let scene = load(&coated(
        json!({"clearcoatFactor": 0.8, "clearcoatRoughnessFactor": 0.3}),
    ));
    let g = pbr(scene.materials()[0].brdf);
    let (w, a) = g.clearcoat();
    assert_eq!(w, 0.8);
    assert!((a - 0.09).abs() < 1e-7, "{a}");
    assert!(!scene.warnings().join("\n").contains(COAT));
    // Defaults: no coat at all (factor 0), and roughness 0 is the sharpest lobe.
    let none = load(&coated(json!({})));
    assert!(matches!(none.materials()[0].brdf, Brdf::Lambert(_)));
    let sharp = load(&coated(json!({"clearcoatFactor": 1.0})));
    assert_eq!(
        pbr(sharp.materials()[0].brdf).clearcoat(),
        (1.0, GltfPbr::MIN_ALPHA)
    );
    // Its textures multiply the factors where a hit lands: the weight in
    // red, the roughness in green (linear); its normal texture is named.
    let mut doc = coated(
        json!({"clearcoatFactor": 0.8, "clearcoatRoughnessFactor": 0.5,
        "clearcoatTexture": {"index": 0}, "clearcoatRoughnessTexture": {"index": 0},
        "clearcoatNormalTexture": {"index": 0}}),
    );
    let sampler = json!({"magFilter": 9728, "wrapS": 33071, "wrapT": 33071});
    let png = crate::gltf_textures::png_rgb(2, 1, &[[255, 255, 0], [51, 128, 0]]);
    doc.texture(&png, sampler);
    // The coat's normal texture asks the primitive for a tangent space
    // (the validator's rule; no core normal texture would make one).
    doc.normals(0, &[[0.0, 1.0, 0.0]; 4]);
    doc.tangents(0, &[[1.0, 0.0, 0.0, 1.0]; 4]);
    let scene = load(&doc);
    let w = scene.warnings().join("\n");
    assert!(w.contains("clearcoatNormalTexture is not read"), "{w}");
    assert!(!w.contains("clearcoatTexture is"), "{w}");
    let (lw, la) = pbr(brdf_at(&scene, -1.0, 0.0)).clearcoat();
    assert!(
        (lw - 0.8).abs() < 1e-6 && (la - 0.25).abs() < 1e-6,
        "{lw} {la}"
    );
    let (rw, ra) = pbr(brdf_at(&scene, 1.0, 0.0)).clearcoat();
    let r = 0.5 * 128.0 / 255.0;
    assert!(
        (rw - 0.16).abs() < 1e-6 && (ra - r * r).abs() < 1e-6,
        "{rw} {ra}"
    );
    // A clear coat texture naming no texture is refused by name.
    let e = load_err(&coated(
        json!({"clearcoatFactor": 1.0, "clearcoatTexture": {"index": 7}}),
    ));
    assert!(e.contains("floor") && e.contains("texture 7"), "{e}");
    // A polished metal stays a mirror; its coat is named as not modelled.
    let mut m = floor(0.9, 0.0, Value::Null);
    m["pbrMetallicRoughness"]["metallicFactor"] = json!(1.0);
    m["extensions"] = json!({ COAT: {"clearcoatFactor": 1.0} });
    let mut doc = floor_scene(m);
    doc.extensions_used.push(COAT);
    let scene = load(&doc);
    assert!(matches!(scene.materials()[0].brdf, Brdf::Mirror(_)));
    let w = scene.warnings().join("\n");
    assert!(w.contains("not modelled on a polished metal"), "{w}");
    // A file may require the extension.
    let doc = coated(json!({"clearcoatFactor": 0.5}));
    let dir = tempfile::tempdir().unwrap();
    let path = doc.write(dir.path());
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    v["extensionsRequired"] = json!([COAT]);
    v["extensionsUsed"] = json!([EXT, COAT]);
    std::fs::write(&path, v.to_string()).unwrap();
    assert_eq!(
        pbr(Scene::load(&path).unwrap().materials()[0].brdf)
            .clearcoat()
            .0,
        0.5
    );
    // Out of range and malformed: refused, naming the material.
    for (coat, what) in [
        (json!({"clearcoatFactor": 1.5}), "clearcoatFactor"),
        (
            json!({"clearcoatRoughnessFactor": -1.0}),
            "clearcoatRoughnessFactor",
        ),
        (json!({"clearcoatFactor": "lots"}), "clearcoatFactor"),
    ] {
        let e = load_err(&coated(coat));
        assert!(e.contains("floor") && e.contains(what), "{e}");
    }
}

#[test]
fn photons_reflect_more_from_a_dark_base_under_a_coat() {
    // A dark matte floor: its coat adds a sheen the light can see, and
    // takes from the base what the sheen reflects. Against the same floor
    // uncoated, the coat raises what reaches the ceiling (the base is
    // dark).
    let coated = {
        let mut m = floor(0.1, 1.0, Value::Null);
        m["extensions"] = json!({COAT: {"clearcoatFactor": 1.0, "clearcoatRoughnessFactor": 0.6}});
        let mut doc = floor_scene(m);
        doc.extensions_used.push(COAT);
        load(&doc)
    };
    let plain = load(&floor_scene(floor(0.1, 1.0, Value::Null)));
    let seed = common::seed(91);
    let (c, c_se) = reflected_up(&coated, seed);
    let (p, p_se) = reflected_up(&plain, seed + 1);
    eprintln!("reflected up: coated {c} +- {c_se}, plain {p} +- {p_se}");
    let se = c_se.hypot(p_se);
    assert!(c - p > 4.0 * se, "the coat reflects: {c} vs {p} (se {se})");
}
