//! `EXT_meshopt_compression` against the files gltfpack 1.3 writes
//! (`npm install gltfpack@1.3.0`), each beside the same pack uncompressed
//! (`assets/blender_scene_instanced.glb`: `gltfpack -i
//! assets/blender_scene.glb -o assets/blender_scene_instanced.glb -mi`):
//!
//! - `assets/blender_scene_meshopt.glb`: `... -mi -c -ce ext` (attributes
//!   and triangles, no filter): the codecs are lossless, so every mesh
//!   must come out bit for bit as the uncompressed pack's, but for where
//!   each triangle starts (the triangle codec may rotate a triangle's
//!   corners, its winding kept);
//! - `assets/blender_scene_meshopt_filters.glb`: `... -mi -cc -ce ext`
//!   (normals by the octahedral filter, instance rotations by the
//!   quaternion one, translations and scales by the exponential one): the
//!   filters re-quantize, so each mesh must match to their precision.

use adaptive_pm::scene::{Mesh, Scene};
use std::path::Path;

fn asset(name: &str) -> Scene {
    let s = Scene::load(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets")
            .join(name),
    )
    .unwrap();
    assert!(s.warnings().is_empty(), "{name}: {:?}", s.warnings());
    s
}

/// The meshes of `s`, in a fixed order (the loader's order follows the
/// file's nodes, which the two packs write alike, but sort to be sure).
/// Each triangle's corners rotated to start at its smallest index (the
/// same triangle, the same winding).
fn rotated(indices: &[[u32; 3]]) -> Vec<[u32; 3]> {
    indices
        .iter()
        .map(|&[a, b, c]| match (a.min(b).min(c), a, b) {
            (m, x, _) if m == x => [a, b, c],
            (m, _, y) if m == y => [b, c, a],
            _ => [c, a, b],
        })
        .collect()
}

fn meshes(s: &Scene) -> Vec<&Mesh> {
    let mut v: Vec<&Mesh> = s.meshes().iter().collect();
    let key = |m: &Mesh| (m.name.clone(), m.positions.first().map(|p| p.to_array()));
    v.sort_by(|a, b| {
        let (ka, kb) = (key(a), key(b));
        ka.0.cmp(&kb.0).then(
            ka.1.unwrap_or_default()
                .partial_cmp(&kb.1.unwrap_or_default())
                .unwrap(),
        )
    });
    v
}

/// Asserts that `a` and `b` hold the same meshes bit for bit (positions,
/// normals, texture coordinates, materials), each triangle with its
/// winding wherever it starts; returns how many meshes.
fn assert_same_meshes(a: &Scene, b: &Scene) -> usize {
    let (ma, mb) = (meshes(a), meshes(b));
    assert_eq!(ma.len(), mb.len());
    let bits = |v: &[glam::Vec3]| {
        v.iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect::<Vec<_>>()
    };
    for (x, y) in ma.iter().zip(&mb) {
        assert_eq!(x.name, y.name);
        assert_eq!(rotated(&x.indices), rotated(&y.indices), "{}", x.name);
        assert_eq!(bits(&x.positions), bits(&y.positions), "{}", x.name);
        assert_eq!(bits(&x.normals), bits(&y.normals), "{}", x.name);
        assert_eq!(x.texcoords, y.texcoords, "{}", x.name);
        assert_eq!(
            a.materials()[x.material].name,
            b.materials()[y.material].name
        );
    }
    ma.len()
}

#[test]
fn compressed_buffer_views_decode_to_the_uncompressed_pack_bit_for_bit() {
    let plain = asset("blender_scene_instanced.glb");
    let packed = asset("blender_scene_meshopt.glb");
    let n = assert_same_meshes(&plain, &packed);
    assert!(n >= 5, "the scene's meshes, its pillars instanced");
    assert_eq!(plain.lights().len(), packed.lights().len());
}

/// A mesh's area, its area-weighted centroid, its bounding box and its
/// area-weighted mean vertex normal: what a renderer sees of it, whatever
/// order its vertices and triangles come in.
fn moments(m: &Mesh) -> (f32, glam::Vec3, [glam::Vec3; 2], glam::Vec3) {
    let (mut area, mut centre, mut normal) = (0.0, glam::Vec3::ZERO, glam::Vec3::ZERO);
    for t in &m.indices {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        let da = 0.5 * (b - a).cross(c - a).length();
        area += da;
        centre += da * (a + b + c) / 3.0;
        if !m.normals.is_empty() {
            normal += da * t.iter().map(|&i| m.normals[i as usize]).sum::<glam::Vec3>() / 3.0;
        }
    }
    let lo = m
        .positions
        .iter()
        .fold(glam::Vec3::INFINITY, |a, p| a.min(*p));
    let hi = m
        .positions
        .iter()
        .fold(glam::Vec3::NEG_INFINITY, |a, p| a.max(*p));
    (area, centre / area, [lo, hi], normal / area)
}

#[test]
fn filtered_views_match_the_uncompressed_pack_to_their_precision() {
    let plain = asset("blender_scene_instanced.glb");
    let packed = asset("blender_scene_meshopt_filters.glb");
    let (a, b) = (meshes(&plain), meshes(&packed));
    assert_eq!(a.len(), b.len());
    // `-cc` orders vertices and triangles its own way: compare what does
    // not depend on the order. The instance transforms pass through the
    // quaternion (16-bit) and exponential filters, the normals through the
    // octahedral one at 8 bits.
    for (ma, mb) in a.iter().zip(&b) {
        assert_eq!(ma.indices.len(), mb.indices.len(), "{}", ma.name);
        let ((aa, ca, ba, na), (ab, cb, bb, nb)) = (moments(ma), moments(mb));
        assert!(
            (aa - ab).abs() < 1e-4 * aa.max(1.0),
            "{}: area {aa} vs {ab}",
            ma.name
        );
        assert!(
            (ca - cb).length() < 1e-3,
            "{}: centroid {ca} vs {cb}",
            ma.name
        );
        for (p, q) in ba.iter().zip(&bb) {
            assert!((*p - *q).length() < 1e-3, "{}: box {p} vs {q}", ma.name);
        }
        assert!(
            (na - nb).length() < 1e-2,
            "{}: mean normal {na} vs {nb}",
            ma.name
        );
    }
}

/// `tests/gltf/meshopt_cornell.gltf`: `gltfpack -i assets/cornell_box.gltf
/// -o meshopt_cornell.gltf -cc -ce ext -kn -km`, its `.bin` then embedded
/// as a data URI. Its fallback buffer has no data of its own (zeros the
/// views are decoded into) in a text file, not a GLB; the box keeps its
/// area, light and materials to gltfpack's quantization.
#[test]
fn a_text_file_with_a_fallback_buffer_loads_the_box() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let box_ = Scene::load(root.join("assets/cornell_box.gltf")).unwrap();
    let packed = Scene::load(root.join("tests/gltf/meshopt_cornell.gltf")).unwrap();
    assert_eq!(packed.triangle_count(), box_.triangle_count());
    let area = |s: &Scene| s.meshes().iter().map(|m| m.area()).sum::<f64>();
    let (a, b) = (area(&box_), area(&packed));
    assert!((a - b).abs() < 1e-3 * a, "area {a} vs {b}");
    let power = |s: &Scene| s.lights().iter().map(|l| l.power()).sum::<glam::Vec3>();
    let (pa, pb) = (power(&box_), power(&packed));
    assert!(
        (pa - pb).abs().max_element() < 2e-3 * pa.max_element(),
        "{pa} vs {pb}"
    );
}

/// `assets/blender_scene_meshopt_khr.glb`: `gltfpack -i
/// assets/blender_scene.glb -o assets/blender_scene_meshopt_khr.glb -mi -cz
/// -ce khr`, the Khronos extension with its version-1 attribute bitstream
/// (control modes, 16-bit channel deltas) at gltfpack's highest level: it
/// decodes to exactly what the vendor extension's pack with the same
/// filters does.
#[test]
fn the_khronos_extensions_version_one_decodes_as_the_vendor_ones_pack() {
    let ext = asset("blender_scene_meshopt_filters.glb");
    let khr = asset("blender_scene_meshopt_khr.glb");
    assert_same_meshes(&ext, &khr);
}

/// `tests/gltf/meshopt_khr_colours.gltf`: gltfpack's `-cc -ce khr -kn -km`
/// over a generated floor with vertex colours (its `.bin` embedded), whose
/// colours go through the Khronos extension's YCoCg colour filter; beside
/// it the same pack uncompressed (`..._plain.gltf`, gltfpack without
/// `-cc`). The filter is lossy to its bits: each colour within 2/255.
#[test]
fn the_colour_filter_gives_the_packs_vertex_colours() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/gltf");
    let packed = Scene::load(root.join("meshopt_khr_colours.gltf")).unwrap();
    let plain = Scene::load(root.join("meshopt_khr_colours_plain.gltf")).unwrap();
    let colours = |s: &Scene| {
        s.meshes()
            .iter()
            .flat_map(|m| m.colors.clone())
            .collect::<Vec<_>>()
    };
    let (a, b) = (colours(&plain), colours(&packed));
    assert!(
        !a.is_empty() && a.len() == b.len(),
        "{} vs {}",
        a.len(),
        b.len()
    );
    for (x, y) in a.iter().zip(&b) {
        assert!((*x - *y).abs().max_element() <= 2.0 / 255.0, "{x} vs {y}");
    }
    assert!(
        a.iter().any(|c| (c.x - c.y).abs() > 0.05),
        "colours that differ by channel"
    );
}
