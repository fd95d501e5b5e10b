//! glTF files read as the specification says: a node with a negative
//! determinant reverses its winding (§3.7.4), a `doubleSided` emitter emits
//! from both faces, strips and fans are triangles, points and lines are
//! skipped with a warning, and a primitive without a material gets the
//! specification's default. Scenes are written here as small JSON files with
//! their geometry in a `data:` buffer.

use adaptive_pm::brdf::Brdf;
use adaptive_pm::embree::Device;
use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
use adaptive_pm::rng::Rng;
use adaptive_pm::scene::{Light, Scene};
use glam::{Mat4, Vec3};
use serde_json::{json, Value};
use std::path::PathBuf;

use crate::common;
use crate::gltf_doc::{square, Doc};
use std::sync::Arc;

/// A file edit, and what the loader's refusal must say.
type Case<'a> = (&'a str, &'a Doc, Box<dyn Fn(&mut Value)>, &'a str);

fn white(doc: &mut Doc) -> usize {
    doc.material(json!({"name": "white", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0}}))
}

fn lamp(doc: &mut Doc, double_sided: bool) -> usize {
    doc.material(
        json!({"name": "lamp", "emissiveFactor": [1.0, 1.0, 1.0], "doubleSided": double_sided,
        "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0}}),
    )
}

/// A floor facing up at y = 0 and a light square 1 above it, authored
/// facing up (`light_up`) and placed by `light_node` (its mesh is set here).
fn floor_and_light(dir: &std::path::Path, light_up: bool, light_node: Value) -> PathBuf {
    let mut doc = Doc::default();
    let (white, lamp) = (white(&mut doc), lamp(&mut doc, false));
    let (p, i) = square(2.0, true);
    let floor = doc.mesh(&p, &i, 4, Some(white));
    doc.node(json!({ "mesh": floor }));
    let (p, i) = square(0.25, light_up);
    let light = doc.mesh(&p, &i, 4, Some(lamp));
    let mut n = light_node;
    n["mesh"] = json!(light);
    doc.node(n);
    doc.write(dir)
}

/// Photons emitted from the scene's only area light: the share whose
/// direction has y < 0, and their count.
fn downward_share(scene: &Scene, n: usize, seed: u64) -> f64 {
    let mut rng = Rng::new(seed);
    let light = &scene.lights()[0];
    let down = (0..n)
        .filter(|_| {
            light
                .sample(rng.next_f32(), rng.next_2d(), rng.next_2d())
                .direction
                .y
                < 0.0
        })
        .count();
    down as f64 / n as f64
}

/// Photons stored on the floor (y = 0) by a classic trace of `n_max` photons.
pub(crate) fn floor_photons(scene: &Scene, n_max: u64, seed: u64) -> u64 {
    let device = Device::new().unwrap();
    let prepared = Arc::new(scene.clone().commit(&device).unwrap());
    let tracer = Tracer::new(Arc::clone(&prepared));
    let mut cfg = TraceConfig::new(Mode::Classic, Budget::NMax(n_max));
    cfg.seed = seed;
    let out = tracer.trace(&cfg).unwrap();
    out.records()
        .iter()
        .filter(|r| r.position.y.abs() < 1e-3 && r.depth == 0)
        .count() as u64
}

#[test]
fn a_mirrored_light_faces_the_floor_like_an_unmirrored_one() {
    let dir = tempfile::tempdir().unwrap();
    let at = [0.0, 1.0, 0.0];
    // Authored facing down, placed as it is: the reference.
    let reference = Scene::load(floor_and_light(
        dir.path(),
        false,
        json!({ "translation": at }),
    ))
    .unwrap();
    // Authored facing up, then mirrored in y: a negative determinant.
    let mirrored = Scene::load(floor_and_light(
        dir.path(),
        true,
        json!({"translation": at, "scale": [1.0, -1.0, 1.0]}),
    ))
    .unwrap();
    // Mirrored in x: the vertices swap places, so the winding as stored
    // turns to face up; the mirror image of a face looking down still looks down.
    let mirrored_x = Scene::load(floor_and_light(
        dir.path(),
        false,
        json!({"translation": at, "scale": [-1.0, 1.0, 1.0]}),
    ))
    .unwrap();
    // Authored facing up, turned 180 degrees about x: a rotation keeps its winding.
    let rotated = Scene::load(floor_and_light(
        dir.path(),
        true,
        json!({"translation": at, "rotation": [1.0, 0.0, 0.0, 0.0]}),
    ))
    .unwrap();
    // Authored up; the point reflection (-1, -1, -1) turns it down, the
    // half turn about x up again: it faces the ceiling.
    let blender = Scene::load(floor_and_light(
        dir.path(),
        true,
        json!({"translation": at, "rotation": [1.0, 0.0, 0.0, 0.0], "scale": [-1.0, -1.0, -1.0]}),
    ))
    .unwrap();
    let n = 4000;
    for (name, scene, down) in [
        ("reference", &reference, true),
        ("mirrored in y", &mirrored, true),
        ("mirrored in x", &mirrored_x, true),
        ("rotated", &rotated, true),
        ("reflected and turned", &blender, false),
    ] {
        let share = downward_share(scene, n, 1);
        let want = if down { 1.0 } else { 0.0 };
        assert_eq!(share, want, "{name}: share of photons emitted downward");
    }

    let n_max = 20_000;
    let seed = common::seed(25_001);
    let reference_count = floor_photons(&reference, n_max, seed);
    assert!(reference_count > 1000, "{reference_count}");
    for (name, scene) in [
        ("mirrored in y", &mirrored),
        ("mirrored in x", &mirrored_x),
        ("rotated", &rotated),
    ] {
        // Two independent runs (other seeds) of the same expected count.
        let count = floor_photons(scene, n_max, seed ^ 0x5eed);
        let sigma = ((reference_count + count) as f64).sqrt();
        common::assert_sigmas(
            &format!("{name} floor photons against the reference"),
            count as f64 - reference_count as f64,
            sigma,
            4.0,
        );
    }
    assert_eq!(
        floor_photons(&blender, n_max, seed),
        0,
        "a light facing away stores nothing on the floor"
    );
}

#[test]
fn a_mirrored_floor_keeps_its_normals_facing_up() {
    let dir = tempfile::tempdir().unwrap();
    let mut doc = Doc::default();
    let (white, lamp) = (white(&mut doc), lamp(&mut doc, false));
    // Authored facing down with down-pointing normals, mirrored in y.
    let (p, i) = square(2.0, false);
    let floor = doc.mesh(&p, &i, 4, Some(white));
    let normals: Vec<u8> = (0..4)
        .flat_map(|_| [0.0f32, -1.0, 0.0])
        .flat_map(|c| c.to_le_bytes())
        .collect();
    let v = doc.view(&normals);
    doc.accessors
        .push(json!({"bufferView": v, "componentType": 5126, "count": 4, "type": "VEC3"}));
    doc.meshes[floor]["primitives"][0]["attributes"]["NORMAL"] = json!(doc.accessors.len() - 1);
    doc.node(json!({"mesh": floor, "scale": [1.0, -1.0, 1.0]}));
    let (p, i) = square(0.25, false);
    let light = doc.mesh(&p, &i, 4, Some(lamp));
    doc.node(json!({"mesh": light, "translation": [0.0, 1.0, 0.0]}));
    let s = Scene::load(doc.write(dir.path())).unwrap();
    let m = &s.meshes()[0];
    for t in 0..m.indices.len() {
        let [a, b, c] = m.triangle(t);
        assert!((b - a).cross(c - a).y > 0.0, "triangle {t} faces down");
        assert!(m.shading_normal(t, 0.3, 0.3).unwrap().y > 0.999);
    }
    assert!(floor_photons(&s, 20_000, 3) > 1000);
}

#[test]
fn a_double_sided_emitter_emits_from_both_faces_and_counts_both_in_its_power() {
    let dir = tempfile::tempdir().unwrap();
    let load = |double_sided: bool| {
        let mut doc = Doc::default();
        let (white, lamp) = (white(&mut doc), lamp(&mut doc, double_sided));
        let (p, i) = square(2.0, true);
        let floor = doc.mesh(&p, &i, 4, Some(white));
        doc.node(json!({ "mesh": floor }));
        let (p, i) = square(0.25, false);
        let light = doc.mesh(&p, &i, 4, Some(lamp));
        doc.node(json!({"mesh": light, "translation": [0.0, 1.0, 0.0]}));
        Scene::load(doc.write(dir.path())).unwrap()
    };
    let (one, two) = (load(false), load(true));
    let (Light::Area(a1), Light::Area(a2)) = (&one.lights()[0], &two.lights()[0]) else {
        panic!("area lights")
    };
    assert!(!a1.emission.two_sided && a2.emission.two_sided);
    // Area 0.25, radiance 1, diffuse: pi * 0.25 a face.
    let face = std::f32::consts::PI * 0.25;
    assert!((a1.power().x - face).abs() < 1e-5, "{}", a1.power());
    assert!((a2.power().x - 2.0 * face).abs() < 1e-5, "{}", a2.power());

    assert_eq!(downward_share(&one, 10_000, 2), 1.0);
    let n = 100_000;
    let share = downward_share(&two, n, common::seed(25_002));
    common::assert_sigmas(
        "share of a two-sided light's photons emitted down",
        share - 0.5,
        (0.25 / n as f64).sqrt(),
        4.0,
    );

    // Radiance leaves the back of a two-sided emitter only.
    let (e1, e2) = (a1.emission, a2.emission);
    assert_eq!(e1.radiance_at(-0.5), Vec3::ZERO);
    assert_eq!(e2.radiance_at(-0.5), e2.radiance_at(0.5));
    assert_eq!(e1.radiance_at(0.5), e2.radiance_at(0.5));
}

#[test]
fn strips_and_fans_are_the_triangles_of_the_list() {
    let dir = tempfile::tempdir().unwrap();
    let load = |indices: &[u32], mode: u32| {
        let mut doc = Doc::default();
        let lamp = lamp(&mut doc, false);
        let (p, _) = square(1.0, false);
        let m = doc.mesh(&p, indices, mode, Some(lamp));
        doc.node(json!({ "mesh": m }));
        Scene::load(doc.write(dir.path())).unwrap()
    };
    let list = load(&[0, 1, 2, 0, 2, 3], 4);
    // A strip 0, 1, 3, 2 makes (0, 1, 3) and (1, 2, 3) once its second is
    // rewound; a fan around 0 makes (1, 2, 0) and (2, 3, 0). Both face down,
    // like the list.
    for (name, scene) in [
        ("strip", load(&[0, 1, 3, 2], 5)),
        ("fan", load(&[0, 1, 2, 3], 6)),
    ] {
        let m = &scene.meshes()[0];
        assert_eq!(m.indices.len(), 2, "{name}");
        assert!((m.area() - list.meshes()[0].area()).abs() < 1e-6, "{name}");
        for t in 0..2 {
            let [a, b, c] = m.triangle(t);
            assert!((b - a).cross(c - a).y < 0.0, "{name} triangle {t} faces up");
        }
        assert_eq!(
            scene.lights()[0].power(),
            list.lights()[0].power(),
            "{name}"
        );
    }
}

#[test]
fn points_and_lines_beside_triangles_are_skipped_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let mut doc = Doc::default();
    let lamp = lamp(&mut doc, false);
    let (p, i) = square(1.0, false);
    let line = [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]];
    let m = doc.primitives(&[
        (&p, &i, 4, Some(lamp)),
        (&line, &[0, 1], 1, None),
        (&line, &[0, 1], 0, None),
    ]);
    doc.meshes[m]["name"] = json!("helpers");
    doc.node(json!({ "mesh": m }));
    let s = Scene::load(doc.write(dir.path())).unwrap();
    assert_eq!(s.triangle_count(), 2);
    assert_eq!(s.warnings().len(), 2, "{:?}", s.warnings());
    for (w, mode) in s.warnings().iter().zip(["Lines", "Points"]) {
        assert!(
            w.contains("`helpers`") && w.contains(mode) && w.contains("skipped"),
            "{w}"
        );
    }
}

#[test]
fn a_primitive_without_material_gets_the_specifications_white_rough_metal() {
    let dir = tempfile::tempdir().unwrap();
    let mut doc = Doc::default();
    let lamp = lamp(&mut doc, false);
    let (p, i) = square(2.0, true);
    let floor = doc.mesh(&p, &i, 4, None);
    doc.node(json!({ "mesh": floor }));
    let (p, i) = square(0.25, false);
    let light = doc.mesh(&p, &i, 4, Some(lamp));
    doc.node(json!({"mesh": light, "translation": [0.0, 1.0, 0.0]}));
    let s = Scene::load(doc.write(dir.path())).unwrap();
    let m = &s.materials()[s.meshes()[0].material];
    assert_eq!(m.name, "default");
    let want = adaptive_pm::brdf::gltf_map::from_gltf_material(
        &adaptive_pm::brdf::gltf_map::GltfMaterial::new(Vec3::ONE, 1.0, 1.0),
    )
    .unwrap();
    assert_eq!(m.brdf, want);
    assert!(!matches!(m.brdf, Brdf::Lambert(_)), "{:?}", m.brdf);
}

/// What the Khronos validator calls invalid, and the loader used to accept.
#[test]
fn files_the_khronos_validator_calls_invalid_are_refused_with_a_reason() {
    let dir = tempfile::tempdir().unwrap();
    let base = || {
        let mut doc = Doc::default();
        let lamp = lamp(&mut doc, false);
        let (p, i) = square(1.0, false);
        doc.mesh(&p, &i, 4, Some(lamp));
        doc
    };
    let write = |doc: &Doc, edit: &dyn Fn(&mut Value)| {
        let path = doc.write(dir.path());
        let mut v: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        edit(&mut v);
        std::fs::write(&path, v.to_string()).unwrap();
        Scene::load(&path)
    };
    let mut one = base();
    one.node(json!({"mesh": 0}));
    assert!(write(&one, &|_| {}).is_ok());
    let mut two = base();
    two.node(json!({"mesh": 0}));
    two.node(json!({"children": [0]}));
    two.node(json!({"children": [0]}));
    let cases: Vec<Case> = vec![
        (
            "projective matrix",
            &one,
            Box::new(|v| {
                v["nodes"][0]["matrix"] = json!([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 1, 0, 0, 0, 0])
            }),
            "bottom row",
        ),
        (
            "sheared matrix",
            &one,
            Box::new(|v| {
                v["nodes"][0]["matrix"] = json!([1, 0, 0, 0, 1, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1])
            }),
            "sheared",
        ),
        (
            "matrix and TRS",
            &one,
            Box::new(|v| {
                v["nodes"][0]["matrix"] = json!([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]);
                v["nodes"][0]["scale"] = json!([2, 2, 2]);
            }),
            "both a matrix",
        ),
        (
            "a root listed twice",
            &one,
            Box::new(|v| v["scenes"][0]["nodes"] = json!([0, 0])),
            "twice among its roots",
        ),
        (
            "a node under two parents",
            &two,
            Box::new(|v| v["scenes"][0]["nodes"] = json!([1, 2])),
            "child of both",
        ),
        (
            "a root that is a child",
            &two,
            Box::new(|v| {
                v["nodes"][2].as_object_mut().unwrap().remove("children");
                v["scenes"][0]["nodes"] = json!([0, 1]);
            }),
            "as a root, but it is a child",
        ),
        (
            "POSITION without bounds",
            &one,
            Box::new(|v| {
                v["accessors"][0].as_object_mut().unwrap().remove("min");
            }),
            "no min and max",
        ),
        (
            "a camera of aspect ratio 0",
            &one,
            Box::new(|v| {
                v["cameras"] = json!([{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1, "aspectRatio": 0.0}}]);
                v["nodes"][0]["camera"] = json!(0);
            }),
            "aspectRatio 0",
        ),
        (
            "a point light of range 0",
            &one,
            Box::new(|v| {
                v["extensionsUsed"] = json!(["KHR_lights_punctual"]);
                v["extensions"] = json!({"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 1.0, "range": 0.0}]}});
                v["nodes"][0]["extensions"] = json!({"KHR_lights_punctual": {"light": 0}});
            }),
            "range 0",
        ),
    ];
    for (name, doc, edit, says) in cases {
        match write(doc, &*edit) {
            Ok(_) => panic!("{name}: accepted"),
            Err(e) => assert!(e.to_string().contains(says), "{name}: {e}"),
        }
    }
}

/// `assets/blender_scene_instanced.glb`: gltfpack 1.3 (`npm install
/// gltfpack@1.3.0`) over the Blender export, `gltfpack -i
/// assets/blender_scene.glb -o assets/blender_scene_instanced.glb -mi`,
/// which turns the three pillars sharing one mesh into GPU instances
/// (`EXT_mesh_gpu_instancing`, required) and quantizes the vertices
/// (`KHR_mesh_quantization`). Each material keeps its meshes, each mesh its
/// triangles, area and place, to the quantization's step.
#[test]
fn gltfpacks_gpu_instances_are_blenders_pillars() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let blender = Scene::load(root.join("assets/blender_scene.glb")).unwrap();
    let packed = Scene::load(root.join("assets/blender_scene_instanced.glb")).unwrap();
    assert!(packed.warnings().is_empty(), "{:?}", packed.warnings());
    assert_eq!(packed.triangle_count(), blender.triangle_count());
    // Per material, its meshes' (triangles, area, bounding-box centre), in
    // the order of their centres' x.
    let meshes = |s: &Scene, material: &str| {
        let mut v: Vec<(usize, f64, Vec3)> = s
            .meshes()
            .iter()
            .filter(|m| s.materials()[m.material].name == material)
            .map(|m| {
                let lo = m.positions.iter().fold(Vec3::INFINITY, |a, p| a.min(*p));
                let hi = m
                    .positions
                    .iter()
                    .fold(Vec3::NEG_INFINITY, |a, p| a.max(*p));
                (m.indices.len(), m.area(), (lo + hi) * 0.5)
            })
            .collect();
        v.sort_by(|a, b| a.2.x.total_cmp(&b.2.x));
        v
    };
    for m in blender.materials() {
        let (a, b) = (meshes(&blender, &m.name), meshes(&packed, &m.name));
        assert_eq!(a.len(), b.len(), "{}", m.name);
        for ((ta, aa, ca), (tb, ab, cb)) in a.iter().zip(&b) {
            assert_eq!(ta, tb, "{}", m.name);
            assert!((aa - ab).abs() < 5e-3 * aa, "{}: area {aa} vs {ab}", m.name);
            assert!(
                (*ca - *cb).length() < 2e-3,
                "{}: centre {ca} vs {cb}",
                m.name
            );
        }
    }
    assert_eq!(meshes(&packed, "blue_clay").len(), 3, "three pillars");
}

/// The scene Blender 3.4's own exporter wrote (`tools/blender_scene.py`):
/// its lamp is mirrored (a negative determinant) and double-sided, so its
/// floor is lit only if both are read; it traces and renders.
#[test]
fn the_blender_export_lights_its_floor_and_renders() {
    use adaptive_pm::render::{render, RenderConfig, RenderMaps};
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/blender_scene.glb");
    let s = Scene::load(file).unwrap();
    let panel = s
        .lights()
        .iter()
        .find_map(|l| match l {
            Light::Area(a) => Some(a),
            _ => None,
        })
        .expect("the emission panel is an area light");
    assert!(panel.emission.two_sided);
    let glass = s.materials().iter().find(|m| m.name == "glass").unwrap();
    assert!(
        matches!(glass.brdf, Brdf::Dielectric(_)),
        "{:?}",
        glass.brdf
    );

    let device = Device::new().unwrap();
    let prepared = Arc::new(s.clone().commit(&device).unwrap());
    let mut cfg = TraceConfig::new(Mode::Classic, Budget::NMax(20_000));
    cfg.seed = 5;
    let out = Tracer::new(Arc::clone(&prepared)).trace(&cfg).unwrap();
    let records = out.records();
    // The floor is the plane y = 0; the panel hangs 2 above it.
    let floor = records.iter().filter(|r| r.position.y.abs() < 1e-3).count();
    assert!(
        floor > 1000,
        "{floor} of {} photons on the floor",
        records.len()
    );

    let maps = RenderMaps::build(&records);
    let mut rc = RenderConfig::new(32, 24);
    rc.spp = 2;
    let image = render(&prepared, Some(&maps), &rc).unwrap();
    let lit = image
        .pixels
        .iter()
        .filter(|p| p.max_element() > 0.0)
        .count();
    assert!(
        lit > image.pixels.len() / 4,
        "{lit} of {} pixels lit",
        image.pixels.len()
    );
    assert!(image.pixels.iter().all(|p| p.is_finite()));
}

#[test]
fn valid_json_the_gltf_crate_is_strict_about_still_loads() {
    let dir = tempfile::tempdir().unwrap();
    let path = floor_and_light(dir.path(), false, json!({ "translation": [0.0, 1.0, 0.0] }));
    let reference = Scene::load(&path).unwrap();
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    // Integers written as floats (JSON has one number type).
    v["scene"] = json!(0.0);
    v["nodes"][0]["mesh"] = json!(0.0);
    v["accessors"][0]["count"] = json!(4e0);
    // An animation the loader does not read, its target a pointer, not a node.
    v["animations"] = json!([{"channels": [{"sampler": 0, "target": {"path": "pointer",
        "extensions": {"KHR_animation_pointer": {"pointer": "/nodes/0/translation"}}}}],
        "samplers": [{"input": 0, "output": 0}]}]);
    // A second, empty scene.
    v["scenes"].as_array_mut().unwrap().push(json!({}));
    let mut text = b"\xEF\xBB\xBF".to_vec();
    text.extend_from_slice(v.to_string().as_bytes());
    std::fs::write(&path, text).unwrap();
    let relaxed = Scene::load(&path).unwrap();
    assert_eq!(relaxed.triangle_count(), reference.triangle_count());
    assert_eq!(relaxed.bounds(), reference.bounds());
    assert_eq!(relaxed.lights().len(), 1);
    // What is not valid JSON at all keeps the JSON reader's own message.
    std::fs::write(&path, b"{\"asset\": ").unwrap();
    let e = Scene::load(&path).unwrap_err();
    let source = std::error::Error::source(&e).map(|s| s.to_string());
    assert!(
        source
            .as_deref()
            .is_some_and(|s| s.contains("EOF while parsing")),
        "{e}: {source:?}"
    );
}

#[test]
fn an_unmodelled_extension_is_a_warning_and_morph_weights_are_applied() {
    let dir = tempfile::tempdir().unwrap();
    let path = floor_and_light(dir.path(), false, json!({ "translation": [0.0, 1.0, 0.0] }));
    let reference = Scene::load(&path).unwrap().meshes()[0].positions.clone();
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    // One morph target whose displacements are the positions themselves:
    // a default weight of 0.5 makes the floor 1.5 times as large.
    let position = v["meshes"][0]["primitives"][0]["attributes"]["POSITION"].clone();
    v["meshes"][0]["primitives"][0]["targets"] = json!([{ "POSITION": position }]);
    v["meshes"][0]["weights"] = json!([0.5]);
    v["materials"][0]["extensions"] =
        json!({"KHR_materials_iridescence": {"iridescenceFactor": 1.0}});
    v["extensionsUsed"] = json!(["KHR_materials_iridescence"]);
    std::fs::write(&path, v.to_string()).unwrap();
    let scene = Scene::load(&path).unwrap();
    let w = scene.warnings().join("\n");
    assert_eq!(
        w.matches("KHR_materials_iridescence is not modelled")
            .count(),
        1,
        "{w}"
    );
    assert!(!w.contains("the file uses"), "named with its material: {w}");
    for (got, r) in scene.meshes()[0].positions.iter().zip(&reference) {
        assert!((*got - 1.5 * *r).length() < 1e-6, "{got} vs 1.5 x {r}");
    }
    // An extension outside the materials (an environment light here) is
    // named once, for the file.
    let mut lit = v.clone();
    lit["extensionsUsed"] = json!(["KHR_materials_iridescence", "EXT_lights_image_based"]);
    std::fs::write(&path, lit.to_string()).unwrap();
    let w = Scene::load(&path).unwrap().warnings().join("\n");
    assert_eq!(
        w.matches("the file uses the extension EXT_lights_image_based, which is not read")
            .count(),
        1,
        "{w}"
    );
    // A node's weights override the mesh's: 0 leaves the floor as stored.
    v["nodes"][0]["weights"] = json!([0.0]);
    std::fs::write(&path, v.to_string()).unwrap();
    assert_eq!(Scene::load(&path).unwrap().meshes()[0].positions, reference);
}

#[test]
fn a_skinned_mesh_stands_where_its_joints_put_it() {
    // The floor square's vertices 0 and 1 hang from joint A (raised by 1),
    // 2 and 3 half from A and half from B (raised by 2): at rest they sit at
    // y = 1 and y = 1.5, wherever the mesh's own node is (it is ignored).
    let mut doc = Doc::default();
    let (white, lamp) = (white(&mut doc), lamp(&mut doc, false));
    let (p, i) = square(2.0, true);
    let floor = doc.mesh(&p, &i, 4, Some(white));
    let joints: Vec<u8> = [[0u8, 0, 0, 0], [0, 0, 0, 0], [0, 1, 0, 0], [0, 1, 0, 0]].concat();
    let weights: Vec<u8> = [
        [1.0f32, 0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0, 0.0],
        [0.5, 0.5, 0.0, 0.0],
        [0.5, 0.5, 0.0, 0.0],
    ]
    .iter()
    .flatten()
    .flat_map(|w| w.to_le_bytes())
    .collect();
    // Joint B's inverse bind undoes a bind pose 10 along x: at rest B sits
    // at (10, 2, 0), so B's matrix is a translation by (0, 2, 0).
    let inverse_binds: Vec<u8> = [
        Mat4::IDENTITY,
        Mat4::from_translation(Vec3::new(-10.0, 0.0, 0.0)),
    ]
    .iter()
    .flat_map(|m| m.to_cols_array())
    .flat_map(|f| f.to_le_bytes())
    .collect();
    let (vj, vw, vb) = (
        doc.view(&joints),
        doc.view(&weights),
        doc.view(&inverse_binds),
    );
    doc.accessors
        .push(json!({"bufferView": vj, "componentType": 5121, "count": 4, "type": "VEC4"}));
    doc.accessors
        .push(json!({"bufferView": vw, "componentType": 5126, "count": 4, "type": "VEC4"}));
    doc.accessors
        .push(json!({"bufferView": vb, "componentType": 5126, "count": 2, "type": "MAT4"}));
    let n = doc.accessors.len();
    let attributes = &mut doc.meshes[floor]["primitives"][0]["attributes"];
    attributes["JOINTS_0"] = json!(n - 3);
    attributes["WEIGHTS_0"] = json!(n - 2);
    // The mesh's node is moved, which a skinned mesh ignores (the
    // validator warns of it); the joints share a root, as it requires.
    doc.node(json!({"mesh": floor, "skin": 0, "translation": [100.0, 0.0, 0.0]}));
    doc.node(json!({"name": "A", "translation": [0.0, 1.0, 0.0]}));
    doc.node(json!({"name": "B", "translation": [10.0, 2.0, 0.0]}));
    doc.node(json!({"name": "armature", "children": [1, 2]}));
    doc.skins
        .push(json!({"joints": [1, 2], "inverseBindMatrices": n - 1}));
    let (p, i) = square(0.25, false);
    let light = doc.mesh(&p, &i, 4, Some(lamp));
    doc.node(json!({"mesh": light, "translation": [0.0, 3.0, 0.0]}));
    doc.roots = Some(vec![0, 3, 4]);
    let dir = tempfile::tempdir().unwrap();
    let scene = Scene::load(doc.write(dir.path())).unwrap();
    let floor = &scene.meshes()[0];
    let want = [
        Vec3::new(-2.0, 1.0, -2.0),
        Vec3::new(2.0, 1.0, -2.0),
        Vec3::new(2.0, 1.5, 2.0),
        Vec3::new(-2.0, 1.5, 2.0),
    ];
    for (got, want) in floor.positions.iter().zip(want) {
        assert!((*got - want).length() < 1e-5, "{got} != {want}");
    }
    assert!(
        !scene.warnings().join(" ").contains("skin"),
        "{:?}",
        scene.warnings()
    );
    // A joint index past the skin's joints is refused by name.
    doc.skins[0]["joints"] = json!([1]);
    doc.accessors[n - 1]["count"] = json!(1);
    let e = Scene::load(doc.write(dir.path())).unwrap_err().to_string();
    assert!(e.contains("skin 0") && e.contains("joint 1"), "{e}");
}

/// Adds an accessor of `count` elements of `kind` over `bytes` (component
/// type `component`, normalized when `normalized`) and returns its index.
fn raw_accessor(doc: &mut Doc, bytes: &[u8], component: u32, count: usize, kind: &str) -> usize {
    let v = doc.view(bytes);
    let normalized = component != 5126;
    doc.accessors
        .push(json!({"bufferView": v, "componentType": component,
        "normalized": normalized, "count": count, "type": kind}));
    doc.accessors.len() - 1
}

fn f32_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|c| c.to_le_bytes()).collect()
}

/// A floor square instanced three times by `EXT_mesh_gpu_instancing`
/// (translations, a quarter turn about y as normalized SHORTs, a scale),
/// under a node moved up by 1, and a lamp; `edit` may change the document
/// and the extension's attributes.
fn instanced_floor(edit: impl FnOnce(&mut Doc, &mut Value)) -> Doc {
    let mut doc = Doc::default();
    let (white, lamp) = (white(&mut doc), lamp(&mut doc, false));
    let (p, i) = square(1.0, true);
    let floor = doc.mesh(&p, &i, 4, Some(white));
    let t = f32_bytes(&[0.0, 0.0, 0.0, 5.0, 0.0, 0.0, 0.0, 0.0, 5.0]);
    let t = raw_accessor(&mut doc, &t, 5126, 3, "VEC3");
    let half = (32767.0 * std::f32::consts::FRAC_1_SQRT_2).round() as i16;
    let r: Vec<u8> = [0, 0, 0, 32767, 0, half, 0, half, 0, 0, 0, 32767i16]
        .iter()
        .flat_map(|c| c.to_le_bytes())
        .collect();
    let r = raw_accessor(&mut doc, &r, 5122, 3, "VEC4");
    let s = f32_bytes(&[1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 2.0, 1.0, 2.0]);
    let s = raw_accessor(&mut doc, &s, 5126, 3, "VEC3");
    let id = raw_accessor(&mut doc, &f32_bytes(&[7.0, 8.0, 9.0]), 5126, 3, "SCALAR");
    let mut attributes = json!({"TRANSLATION": t, "ROTATION": r, "SCALE": s, "_ID": id});
    edit(&mut doc, &mut attributes);
    doc.node(json!({"mesh": floor, "translation": [0.0, 1.0, 0.0],
        "extensions": {"EXT_mesh_gpu_instancing": {"attributes": attributes}}}));
    let (p, i) = square(0.5, false);
    let l = doc.mesh(&p, &i, 4, Some(lamp));
    doc.node(json!({"mesh": l, "translation": [0.0, 3.0, 0.0]}));
    doc.extensions_used.push("EXT_mesh_gpu_instancing");
    doc
}

#[test]
fn gpu_instances_place_copies_of_a_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Scene::load(instanced_floor(|_, _| {}).write(dir.path())).unwrap();
    assert!(scene.warnings().is_empty(), "{:?}", scene.warnings());
    let meshes = scene.meshes();
    assert_eq!(meshes.len(), 4, "three instances and the lamp");
    let (p, _) = square(1.0, true);
    let node = Mat4::from_translation(Vec3::Y);
    let quarter = glam::Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    let instances = [
        Mat4::IDENTITY,
        Mat4::from_rotation_translation(quarter, Vec3::new(5.0, 0.0, 0.0)),
        Mat4::from_scale_rotation_translation(
            Vec3::new(2.0, 1.0, 2.0),
            glam::Quat::IDENTITY,
            Vec3::new(0.0, 0.0, 5.0),
        ),
    ];
    for (mesh, instance) in meshes.iter().zip(instances) {
        for (got, local) in mesh.positions.iter().zip(p) {
            let want = (node * instance).transform_point3(Vec3::from(local));
            // The quarter turn is stored as 16-bit normalized integers.
            assert!(
                (*got - want).length() < 1e-4,
                "{}: {got} vs {want}",
                mesh.name
            );
        }
    }
    // A file that requires the extension loads the same.
    let path = instanced_floor(|_, _| {}).write(dir.path());
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    v["extensionsRequired"] = json!(["EXT_mesh_gpu_instancing"]);
    std::fs::write(&path, v.to_string()).unwrap();
    assert_eq!(Scene::load(&path).unwrap().meshes(), meshes);
}

#[test]
fn bad_gpu_instances_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let refused = |edit: &dyn Fn(&mut Doc, &mut Value), words: &[&str]| {
        let doc = instanced_floor(|d, a| edit(d, a));
        let e = Scene::load(doc.write(dir.path())).unwrap_err().to_string();
        assert!(words.iter().all(|w| e.contains(w)), "{words:?}: {e}");
    };
    refused(
        &|d, a| {
            let two = raw_accessor(d, &f32_bytes(&[0.0; 6]), 5126, 2, "VEC3");
            a["SCALE"] = json!(two);
        },
        &["node 0", "one count", "SCALE has 2"],
    );
    refused(
        &|_, a| a["COLOR"] = json!(0),
        &["node 0", "attribute `COLOR` is not supported"],
    );
    refused(
        &|_, a| a["TRANSLATION"] = json!(99),
        &["node 0", "TRANSLATION names no accessor"],
    );
    refused(
        &|d, a| {
            let nan = raw_accessor(
                d,
                &f32_bytes(&[0.0, f32::NAN, 0.0].repeat(3)),
                5126,
                3,
                "VEC3",
            );
            a["TRANSLATION"] = json!(nan);
        },
        &["node 0", "TRANSLATION holds NaN"],
    );
    // Instances (zeros: no bufferView) count as node instances, and
    // multiply their mesh's triangles: both bounds hold before a vertex is
    // read.
    let instances = |count: u64, triangles: usize| {
        move |d: &mut Doc, a: &mut Value| {
            d.accessors
                .push(json!({"componentType": 5126, "count": count, "type": "VEC3"}));
            *a = json!({ "TRANSLATION": d.accessors.len() - 1 });
            let (p, idx) = square(1.0, true);
            let many: Vec<u32> = idx.iter().copied().cycle().take(3 * triangles).collect();
            let m = d.mesh(&p, &many, 4, Some(0));
            d.meshes[0] = d.meshes[m].clone();
        }
    };
    refused(
        &instances(1 << 21, 2),
        &["scene 0 expands to 2097153 node instances"],
    );
    // 700 000 instances of 32 triangles, and the lamp's 2.
    refused(
        &instances(700_000, 32),
        &["scene 0 expands to 22400002 triangles, over the limit"],
    );
}
