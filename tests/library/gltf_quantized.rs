//! `KHR_mesh_quantization`: a quantized copy of a small scene (positions as
//! 8- or 16-bit integers, signed or not, normalized or not, the node's
//! transform dequantizing them as gltfpack writes it; normals as normalized
//! bytes) loads to the float scene's triangles within the quantization step
//! and lights its floor as the float scene does. Storage the extension does
//! not allow is refused naming the accessor.

use crate::gltf_textures::png_rgb;
use adaptive_pm::scene::Scene;
use glam::Vec3;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

use crate::common;
use crate::gltf_conformance::floor_photons;
use crate::gltf_doc::Doc;

const BYTE: u32 = 5120;
const UNSIGNED_BYTE: u32 = 5121;
const SHORT: u32 = 5122;
const UNSIGNED_SHORT: u32 = 5123;
const FLOAT: u32 = 5126;

/// How a test stores POSITION.
#[derive(Clone, Copy, Debug)]
struct Storage {
    component: u32,
    normalized: bool,
}

impl Storage {
    /// The integers used: the signed ones stop at -127 (or -32767), the
    /// lowest value whose normalized form is not clamped.
    fn range(self) -> (f32, f32) {
        match self.component {
            BYTE => (-127.0, 127.0),
            UNSIGNED_BYTE => (0.0, 255.0),
            SHORT => (-32767.0, 32767.0),
            _ => (0.0, 65535.0),
        }
    }

    fn bytes(self, q: f32) -> Vec<u8> {
        match self.component {
            BYTE => (q as i8).to_le_bytes().to_vec(),
            UNSIGNED_BYTE => (q as u8).to_le_bytes().to_vec(),
            SHORT => (q as i16).to_le_bytes().to_vec(),
            _ => (q as u16).to_le_bytes().to_vec(),
        }
    }

    /// What one integer step is worth before the node's scale.
    fn unit(self) -> f32 {
        if self.normalized {
            self.range().1
        } else {
            1.0
        }
    }
}

/// Every storage the extension allows for POSITION besides FLOAT.
fn storages() -> Vec<Storage> {
    let mut all = Vec::new();
    for component in [BYTE, UNSIGNED_BYTE, SHORT, UNSIGNED_SHORT] {
        for normalized in [false, true] {
            all.push(Storage {
                component,
                normalized,
            });
        }
    }
    all
}

/// `positions` quantized: the integers, padded to 4-byte elements, and the
/// node scale and translation that map them back (world = t + s * value).
struct Quantized {
    bytes: Vec<u8>,
    stride: usize,
    min: [i64; 3],
    max: [i64; 3],
    scale: f32,
    translation: Vec3,
}

fn quantize(positions: &[[f32; 3]], storage: Storage) -> Quantized {
    let lo = positions
        .iter()
        .fold(Vec3::INFINITY, |m, &p| m.min(p.into()));
    let hi = positions
        .iter()
        .fold(Vec3::NEG_INFINITY, |m, &p| m.max(p.into()));
    let (qlo, qhi) = storage.range();
    let unit = storage.unit();
    // A uniform scale, as the extension recommends (normals keep their direction).
    let scale = (hi - lo).max_element() / ((qhi - qlo) / unit);
    let translation = lo - scale * (qlo / unit);
    let size = storage.bytes(0.0).len();
    let stride = (3 * size).next_multiple_of(4);
    let (mut bytes, mut min, mut max) = (Vec::new(), [qhi as i64; 3], [qlo as i64; 3]);
    for p in positions {
        let mut element = Vec::new();
        for k in 0..3 {
            let q = ((p[k] - translation[k]) / scale * unit)
                .round()
                .clamp(qlo, qhi);
            min[k] = min[k].min(q as i64);
            max[k] = max[k].max(q as i64);
            element.extend(storage.bytes(q));
        }
        element.resize(stride, 0);
        bytes.extend(element);
    }
    Quantized {
        bytes,
        stride,
        min,
        max,
        scale,
        translation,
    }
}

/// A 4 x 4 floor facing up at y = 0, of four triangles around a vertex off
/// every quantization grid; a lamp facing down 1 above it.
fn floor() -> (Vec<[f32; 3]>, Vec<u32>) {
    let p = vec![
        [-2.0, 0.0, -2.0],
        [2.0, 0.0, -2.0],
        [2.0, 0.0, 2.0],
        [-2.0, 0.0, 2.0],
        [0.3137, 0.0, -0.7771],
    ];
    (p, vec![4, 1, 0, 4, 2, 1, 4, 3, 2, 4, 0, 3])
}

fn lamp() -> (Vec<[f32; 3]>, Vec<u32>) {
    let h = 0.25;
    let p = vec![[-h, 0.0, -h], [h, 0.0, -h], [h, 0.0, h], [-h, 0.0, h]];
    (p, vec![0, 1, 2, 0, 2, 3])
}

/// Adds a mesh of one triangle list, its POSITION stored as `storage`
/// (`None`: FLOAT), placed at `at`; `normal_up` adds a NORMAL of (0, 1, 0)
/// for every vertex as normalized BYTEs.
fn add_mesh(
    doc: &mut Doc,
    (positions, indices): (Vec<[f32; 3]>, Vec<u32>),
    material: usize,
    at: Vec3,
    storage: Option<Storage>,
    normal_up: bool,
) {
    let mesh = match storage {
        None => {
            let m = doc.mesh(&positions, &indices, 4, Some(material));
            doc.node(json!({"mesh": m, "translation": at.to_array()}));
            m
        }
        Some(s) => {
            let q = quantize(&positions, s);
            let v = doc.view(&q.bytes);
            doc.views[v]["byteStride"] = json!(q.stride);
            doc.accessors
                .push(json!({"bufferView": v, "componentType": s.component,
                "normalized": s.normalized, "count": positions.len(), "type": "VEC3",
                "min": q.min, "max": q.max}));
            let position = doc.accessors.len() - 1;
            let bytes: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
            let v = doc.view(&bytes);
            doc.accessors
                .push(json!({"bufferView": v, "componentType": 5125,
                "count": indices.len(), "type": "SCALAR"}));
            doc.meshes
                .push(json!({"primitives": [{"attributes": {"POSITION": position},
                "indices": doc.accessors.len() - 1, "material": material}]}));
            let m = doc.meshes.len() - 1;
            doc.node(
                json!({"mesh": m, "translation": (at + q.translation).to_array(),
                "scale": [q.scale, q.scale, q.scale]}),
            );
            m
        }
    };
    if normal_up {
        let bytes: Vec<u8> = positions.iter().flat_map(|_| [0, 127, 0, 0]).collect();
        let v = doc.view(&bytes);
        doc.views[v]["byteStride"] = json!(4);
        doc.accessors
            .push(json!({"bufferView": v, "componentType": BYTE,
            "normalized": true, "count": positions.len(), "type": "VEC3"}));
        doc.meshes[mesh]["primitives"][0]["attributes"]["NORMAL"] = json!(doc.accessors.len() - 1);
    }
}

/// The floor and lamp scene, its positions stored as `storage` (`None`:
/// FLOAT), written into `dir`; the extension is declared (used and required)
/// whenever anything is quantized.
fn scene_doc(storage: Option<Storage>, normal_up: bool) -> Doc {
    let mut doc = Doc::default();
    let white = doc.material(json!({"name": "white", "pbrMetallicRoughness":
        {"baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0}}));
    let lamp_m = doc.material(json!({"name": "lamp", "emissiveFactor": [1.0, 1.0, 1.0],
        "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0}}));
    add_mesh(&mut doc, floor(), white, Vec3::ZERO, storage, normal_up);
    add_mesh(&mut doc, lamp(), lamp_m, Vec3::Y, storage, false);
    if storage.is_some() || normal_up {
        doc.extensions_used.push("KHR_mesh_quantization");
    }
    doc
}

/// Writes `doc` into `dir` (requiring the extension when it uses it: `Doc::write`).
fn write(doc: &Doc, dir: &Path) -> PathBuf {
    doc.write(dir)
}

fn edit(path: &Path, change: impl Fn(&mut Value)) {
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    change(&mut v);
    std::fs::write(path, v.to_string()).unwrap();
}

fn load(doc: &Doc) -> Scene {
    let dir = tempfile::tempdir().unwrap();
    Scene::load(write(doc, dir.path())).unwrap()
}

/// The largest distance, coordinate by coordinate, between the two scenes'
/// triangle corners.
fn largest_difference(a: &Scene, b: &Scene) -> f32 {
    assert_eq!(a.meshes().len(), b.meshes().len());
    let mut worst = 0.0f32;
    for (ma, mb) in a.meshes().iter().zip(b.meshes()) {
        assert_eq!(ma.indices.len(), mb.indices.len());
        for t in 0..ma.indices.len() {
            for (pa, pb) in ma.triangle(t).iter().zip(mb.triangle(t)) {
                worst = worst.max((*pa - pb).abs().max_element());
            }
        }
    }
    worst
}

#[test]
fn quantized_positions_are_the_float_triangles_within_half_a_step() {
    let float = load(&scene_doc(None, false));
    for storage in storages() {
        let scene = load(&scene_doc(Some(storage), false));
        // The floor's step: 4 metres over the integer range.
        let (lo, hi) = storage.range();
        let step = 4.0 / (hi - lo);
        let worst = largest_difference(&float, &scene);
        assert!(
            worst <= 0.5 * step + 1e-5,
            "{storage:?}: corners differ by {worst}, half a step is {}",
            0.5 * step
        );
        // Not trivially equal: the off-grid vertex moved, by at most half a step.
        if step > 1e-3 {
            assert!(worst > 0.0, "{storage:?}");
        }
    }
}

#[test]
fn a_quantized_floor_is_lit_like_the_float_one() {
    let n_max = 20_000;
    let seed = common::seed(26_001);
    let reference = floor_photons(&load(&scene_doc(None, false)), n_max, seed);
    assert!(reference > 1000, "{reference}");
    for storage in storages() {
        let count = floor_photons(&load(&scene_doc(Some(storage), true)), n_max, seed ^ 0x5eed);
        let sigma = ((reference + count) as f64).sqrt();
        common::assert_sigmas(
            &format!("{storage:?} floor photons against the float scene's"),
            count as f64 - reference as f64,
            sigma,
            4.0,
        );
    }
}

#[test]
fn normals_stored_as_normalized_bytes_point_up() {
    let scene = load(&scene_doc(None, true));
    let floor = &scene.meshes()[0];
    assert_eq!(floor.normals.len(), 5);
    for n in &floor.normals {
        assert!((*n - Vec3::Y).length() < 1e-6, "{n}");
    }
    // Under a quantized position's scale too (the normal matrix's inverse
    // scale is normalized away).
    let scene = load(&scene_doc(Some(storages()[0]), true));
    for n in &scene.meshes()[0].normals {
        assert!((*n - Vec3::Y).length() < 1e-6, "{n}");
    }
}

/// A file edit, and the words its refusal must hold.
type Refusal = (
    &'static str,
    Box<dyn Fn(&mut Value)>,
    &'static [&'static str],
);

#[test]
fn storage_the_extension_does_not_allow_is_refused_naming_the_accessor() {
    let short = Storage {
        component: SHORT,
        normalized: false,
    };
    let cases: Vec<Refusal> = vec![
        (
            "quantized positions without the extension",
            Box::new(|v| {
                let o = v.as_object_mut().unwrap();
                o.remove("extensionsUsed");
                o.remove("extensionsRequired");
            }),
            &[
                "accessor 0",
                "POSITION",
                "stores SHORT",
                "KHR_mesh_quantization",
            ],
        ),
        (
            "NORMAL as BYTE, not normalized",
            Box::new(|v| v["accessors"][2]["normalized"] = json!(false)),
            &[
                "accessor 2",
                "NORMAL",
                "stores BYTE",
                "normalized BYTE or SHORT",
            ],
        ),
        (
            "NORMAL as UNSIGNED_BYTE",
            Box::new(|v| v["accessors"][2]["componentType"] = json!(UNSIGNED_BYTE)),
            &["accessor 2", "normalized UNSIGNED_BYTE"],
        ),
        (
            "POSITION as UNSIGNED_INT",
            Box::new(|v| v["accessors"][0]["componentType"] = json!(5125)),
            &["accessor 0", "UNSIGNED_INT", "POSITION may be"],
        ),
        (
            "POSITION as normalized FLOAT",
            Box::new(|v| {
                v["accessors"][0]["componentType"] = json!(FLOAT);
                v["accessors"][0]["normalized"] = json!(true);
            }),
            &["accessor 0", "normalized FLOAT"],
        ),
        (
            "POSITION as VEC4",
            Box::new(|v| v["accessors"][0]["type"] = json!("VEC4")),
            &["accessor 0", "is Vec4, not Vec3"],
        ),
        (
            "a 3-byte NORMAL without byteStride",
            Box::new(|v| {
                let view = v["accessors"][2]["bufferView"].as_u64().unwrap() as usize;
                v["bufferViews"][view]
                    .as_object_mut()
                    .unwrap()
                    .remove("byteStride");
            }),
            &["accessor 2", "3-byte elements", "aligned to 4 bytes"],
        ),
    ];
    let dir = tempfile::tempdir().unwrap();
    for (name, change, words) in cases {
        let path = write(&scene_doc(Some(short), true), dir.path());
        edit(&path, &*change);
        let e = match Scene::load(&path) {
            Ok(_) => panic!("{name}: loaded"),
            Err(e) => e.to_string(),
        };
        for w in words {
            assert!(e.contains(w), "{name}: `{e}` lacks `{w}`");
        }
    }
}

#[test]
fn quantized_texture_coordinates_are_read_as_their_values() {
    // Per storage: the integers stored for the floor's five vertices, and
    // what one is worth (normalized: 1 / its maximum; otherwise 1).
    let cases: [(u32, bool, [[i32; 2]; 5], f32); 4] = [
        (
            UNSIGNED_BYTE,
            true,
            [[0, 0], [255, 0], [255, 255], [0, 255], [128, 64]],
            1.0 / 255.0,
        ),
        (
            UNSIGNED_SHORT,
            true,
            [[0, 0], [65535, 0], [65535, 65535], [0, 65535], [32768, 1]],
            1.0 / 65535.0,
        ),
        (
            BYTE,
            true,
            [[-127, 0], [127, 0], [127, 127], [0, 127], [-128, 5]],
            1.0 / 127.0,
        ),
        (SHORT, false, [[0, 0], [4, 0], [4, 4], [0, 4], [-2, 1]], 1.0),
    ];
    for (component, normalized, stored, unit) in cases {
        let storage = Storage {
            component,
            normalized,
        };
        let mut doc = scene_doc(None, false);
        doc.extensions_used.push("KHR_mesh_quantization");
        let texture = doc.texture(&png_rgb(1, 1, &[[255; 3]]), json!({}));
        doc.materials[0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": texture});
        let mut bytes = Vec::new();
        for uv in stored {
            let mut element: Vec<u8> = uv.iter().flat_map(|&c| storage.bytes(c as f32)).collect();
            element.resize(4, 0);
            bytes.extend(element);
        }
        let v = doc.view(&bytes);
        doc.views[v]["byteStride"] = json!(4);
        doc.accessors
            .push(json!({"bufferView": v, "componentType": component,
            "normalized": normalized, "count": 5, "type": "VEC2"}));
        doc.meshes[0]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(doc.accessors.len() - 1);
        let scene = load(&doc);
        let read = &scene.meshes()[0].texcoords[0];
        for (got, want) in read.iter().zip(stored) {
            // Normalized: the extension's max(c / 127, -1), so -128 is -1.
            let want = glam::Vec2::new(want[0] as f32, want[1] as f32) * unit;
            let want = if normalized {
                want.max(glam::Vec2::splat(-1.0))
            } else {
                want
            };
            assert!(
                (*got - want).abs().max_element() < 1e-7,
                "{storage:?}: {got} != {want}"
            );
        }
    }
}

/// Generated files kept in the repository, so that the Khronos validator
/// (`scripts/ci-gltf-validator.sh`, which reads tracked files) checks what
/// the generator writes: 3-byte positions padded to 4, normalized BYTE
/// normals, and non-normalized UNSIGNED_SHORT positions.
const KEPT: [(&str, Storage); 2] = [
    (
        "tests/gltf/quantized_byte_normalized.gltf",
        Storage {
            component: BYTE,
            normalized: true,
        },
    ),
    (
        "tests/gltf/quantized_unsigned_short.gltf",
        Storage {
            component: UNSIGNED_SHORT,
            normalized: false,
        },
    ),
];

#[test]
fn the_kept_quantized_files_are_the_generators() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    for (file, storage) in KEPT {
        let made = std::fs::read(write(&scene_doc(Some(storage), true), dir.path())).unwrap();
        let kept = root.join(file);
        if std::env::var_os("ADAPTIVE_PM_WRITE_FIXTURES").is_some() {
            std::fs::create_dir_all(kept.parent().unwrap()).unwrap();
            std::fs::write(&kept, &made).unwrap();
        }
        let on_disk = std::fs::read(&kept).unwrap_or_default();
        assert!(
            on_disk == made,
            "{file} is not the generator's output: rerun with ADAPTIVE_PM_WRITE_FIXTURES=1"
        );
        assert!(Scene::load(&kept).is_ok(), "{file}");
    }
}
