//! glTF `alphaMode: MASK` cut-outs: where `baseColorFactor.a *
//! baseColorTexture.a` is below `alphaCutoff`, a surface is a hole that every
//! ray passes through (Embree's intersection and occlusion filters,
//! `src/embree/filter.rs`). This module: the light that gets through, and
//! the scenes the other two share (`gltf_alpha_mask_rays`: single rays and
//! packets through the holes; `gltf_alpha_mask_refusals`: BLEND and what is
//! refused).
//!
//! The scene of most tests: a black floor (4 x 4, facing up at y = 0) under
//! a lamp (1 x 1, facing down at y = 2), and between them a black plane
//! (4 x 4 at y = 1, its texture coordinates (0, 0) at (-2, -2) and (1, 1) at
//! (2, 2)) whose material is the one under test. Everything is black, so the
//! photons stored on the floor are the lamp's direct light that got past
//! the plane, and their power is the floor's irradiance times its area.
//!
//! Exact checks (fixed seeds): a plane that is all hole leaves the floor's
//! photons bit for bit those of the scene without it; an opaque one stores
//! none; thread counts, batch sizes and single rays give the same maps.
//! Statistical ones (`common::seed`, their noise measured from the photons'
//! own spread, 4 sigma): a 50 % checkerboard passes half the light; the
//! photon renderer agrees with the path tracer on a Cornell box with a fence.

use adaptive_pm::brdf::{Brdf, Lambert};
use adaptive_pm::embree::{thread_pool, Device};
use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
use adaptive_pm::scene::{
    AlphaMask, Filter, Material, PreparedScene, Sampler, Scene, TexTransform, Texture, TextureRef,
};
use glam::Vec3;
use serde_json::{json, Value};
use std::sync::Arc;

use crate::common;
use crate::fixtures::OneByOne;
use crate::gltf_doc::{square, Doc};

/// An 8-bit RGBA PNG of `w x h` pixels.
pub(crate) fn png_rgba(w: u32, h: u32, rgba: &[[u8; 4]]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, w, h);
    enc.set_color(png::ColorType::Rgba);
    enc.set_depth(png::BitDepth::Eight);
    let data: Vec<u8> = rgba.iter().flatten().copied().collect();
    enc.write_header().unwrap().write_image_data(&data).unwrap();
    out
}

/// Texel `(i, j)` of an `n x n` checkerboard: opaque where `i + j` is even,
/// clear (alpha 0) where it is odd; white, which alpha masking must not read
/// as colour.
pub(crate) fn checker_texels(n: u32) -> Vec<[u8; 4]> {
    (0..n * n)
        .map(|k| {
            let (i, j) = (k % n, k / n);
            [255, 255, 255, if (i + j) % 2 == 0 { 255 } else { 0 }]
        })
        .collect()
}

/// Checker squares across the plane (each 4 / 32 = 0.125 wide).
pub(crate) const CHECKS: u32 = 32;

pub(crate) fn checker_png() -> Vec<u8> {
    png_rgba(CHECKS, CHECKS, &checker_texels(CHECKS))
}

/// Whether the checkerboard is clear over the plane's point `(x, z)`.
pub(crate) fn checker_clear(x: f32, z: f32) -> bool {
    let cell = |c: f32| ((c + 2.0) / 4.0 * CHECKS as f32).floor() as i64;
    (cell(x) + cell(z)) % 2 == 1
}

/// A black matte material named `name`.
pub(crate) fn black(name: &str) -> Value {
    json!({"name": name, "pbrMetallicRoughness":
        {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0}})
}

/// The plane's material: black, with alpha `factor` and `mode`, the
/// checkerboard (texture 0) when `textured`.
pub(crate) fn plane_material(mode: &str, factor: f32, textured: bool) -> Value {
    let mut m = json!({"name": "fence", "alphaMode": mode, "pbrMetallicRoughness":
        {"baseColorFactor": [0.0, 0.0, 0.0, factor], "metallicFactor": 0.0}});
    if textured {
        m["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    }
    m
}

/// The floor, the lamp and, when `plane` is given, the plane with that
/// material (module docs). `sampler` is the checkerboard's sampler, when the
/// plane reads it.
pub(crate) fn fence_scene(plane: Option<Value>, sampler: Option<Value>) -> Doc {
    let mut doc = Doc::default();
    if let Some(s) = sampler {
        doc.texture(&checker_png(), s);
    }
    let floor_m = doc.material(black("floor"));
    let lamp = doc.material(json!({"name": "lamp", "emissiveFactor": [1.0, 1.0, 1.0],
        "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0}}));
    let (p, i) = square(2.0, true);
    let f = doc.mesh(&p, &i, 4, Some(floor_m));
    doc.node(json!({ "mesh": f }));
    let (p, i) = square(0.5, false);
    let l = doc.mesh(&p, &i, 4, Some(lamp));
    doc.node(json!({"mesh": l, "translation": [0.0, 2.0, 0.0]}));
    if let Some(m) = plane {
        let plane_m = doc.material(m);
        let (p, i) = square(2.0, true);
        let pl = doc.mesh(&p, &i, 4, Some(plane_m));
        doc.texcoords(pl, &[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        doc.node(json!({"mesh": pl, "translation": [0.0, 1.0, 0.0]}));
    }
    doc
}

pub(crate) fn load(doc: &Doc) -> Scene {
    let dir = tempfile::tempdir().unwrap();
    Scene::load(doc.write(dir.path())).unwrap()
}

pub(crate) fn load_err(doc: &Doc) -> String {
    let dir = tempfile::tempdir().unwrap();
    common::chain(&Scene::load(doc.write(dir.path())).unwrap_err())
}

pub(crate) fn checkered(mode: &str) -> Scene {
    load(&fence_scene(
        Some(plane_material(mode, 1.0, true)),
        Some(json!({})),
    ))
}

/// The photons a Classic trace of `n` photons stores on the floor (depth 0,
/// y = 0), as `(x, z, power)` sorted, with their total power and its
/// standard error (a sum of independent photons: the root of the sum of
/// squares).
pub(crate) fn floor_photons(scene: &Scene, n: u64, seed: u64) -> (Vec<[u32; 3]>, f64, f64) {
    let device = Device::new().unwrap();
    let tracer = Tracer::new(Arc::new(scene.clone().commit(&device).unwrap()));
    let mut cfg = TraceConfig::new(Mode::Classic, Budget::NMax(n));
    cfg.seed = seed;
    let out = tracer.trace(&cfg).unwrap();
    let floor: Vec<_> = out
        .records()
        .into_iter()
        .filter(|r| r.depth == 0 && r.position.y.abs() < 1e-3)
        .collect();
    let sum: f64 = floor.iter().map(|r| f64::from(r.power.x)).sum();
    let var: f64 = floor.iter().map(|r| f64::from(r.power.x).powi(2)).sum();
    let mut keys: Vec<[u32; 3]> = floor
        .iter()
        .map(|r| {
            [
                r.position.x.to_bits(),
                r.position.z.to_bits(),
                r.power.x.to_bits(),
            ]
        })
        .collect();
    keys.sort_unstable();
    (keys, sum, var.sqrt())
}

#[test]
fn a_factor_below_the_cutoff_is_no_plane_and_one_above_is_a_wall() {
    let none = load(&fence_scene(None, None));
    let hole = load(&fence_scene(Some(plane_material("MASK", 0.2, false)), None));
    let wall = load(&fence_scene(Some(plane_material("MASK", 0.8, false)), None));
    // The factor alone, no texture: the default cut-off 0.5.
    let fence = hole.meshes()[2].material;
    let mask = hole.alpha_mask(fence).expect("MASK is read");
    assert_eq!((mask.cutoff, mask.factor, mask.texture), (0.5, 0.2, None));
    assert!(hole.mesh_has_holes(2) && !wall.mesh_has_holes(2));
    assert!(hole.warnings().is_empty(), "{:?}", hole.warnings());
    let seed = 11;
    let (open, open_sum, _) = floor_photons(&none, 100_000, seed);
    let (through, through_sum, _) = floor_photons(&hole, 100_000, seed);
    // Every photon's path is the same as without the plane: the floor's
    // photons bit for bit.
    assert!(open.len() > 20_000, "{} floor photons", open.len());
    assert_eq!(
        through, open,
        "a plane that is all hole changed the floor's photons"
    );
    assert_eq!(through_sum, open_sum);
    // A wall: no direct light on the floor at all.
    let (blocked, _, _) = floor_photons(&wall, 100_000, seed);
    assert!(blocked.is_empty(), "{} photons under a wall", blocked.len());
}

#[test]
fn a_checkerboard_passes_half_the_light() {
    // The lamp, the floor and the plane are symmetric under x -> -x, which
    // maps the 32 x 32 checkerboard onto its complement (31 - i has the
    // other parity), bilinear filtering and the 0.5 cut-off included: the
    // clear and the opaque squares pass the same power in expectation, and
    // together all of it. So the floor receives exactly half of what it
    // receives without the plane (and an opaque plane passes none).
    let none = load(&fence_scene(None, None));
    let checker = checkered("MASK");
    let n = 200_000;
    let (_, c, c_se) = floor_photons(&checker, n, common::seed(21));
    let (_, o, o_se) = floor_photons(&none, n, common::seed(22));
    eprintln!("floor power: checker {c} +- {c_se}, no plane {o} +- {o_se}");
    let sigma = c_se.hypot(0.5 * o_se);
    common::assert_sigmas("checker vs half the open floor", c - 0.5 * o, sigma, 4.0);
    // Not vacuous: the noise is well under the effect of ignoring the mask.
    assert!(8.0 * sigma < 0.5 * o, "sigma {sigma} vs {o}");
}

#[test]
fn maps_through_holes_are_the_same_on_any_threads_batch_and_kernel() {
    let scene = checkered("MASK");
    let device = Device::new().unwrap();
    let rt = scene.embree_geometry(&device).unwrap();
    let mut cfg = TraceConfig::new(Mode::Adaptive, Budget::NMax(30_000));
    cfg.seed = 9;
    let run = |cfg: &TraceConfig, threads: usize, one_by_one: bool| {
        let pool = thread_pool(threads).unwrap();
        pool.install(|| {
            let out = if one_by_one {
                let single = OneByOne(scene.embree_geometry(&device).unwrap());
                let prepared = PreparedScene::new(scene.clone(), single).unwrap();
                Tracer::new(prepared).trace(cfg).unwrap()
            } else {
                let prepared = PreparedScene::new(scene.clone(), &rt).unwrap();
                Tracer::new(prepared).trace(cfg).unwrap()
            };
            (out.report.stored, out.into_map().checksum())
        })
    };
    let base = run(&cfg, 1, false);
    assert!(base.0 > 10_000, "{} stored", base.0);
    assert_eq!(run(&cfg, 2, false), base, "two threads");
    let mut odd = cfg.clone();
    odd.batch = 777;
    assert_eq!(run(&odd, 2, false), base, "batch 777");
    assert_eq!(run(&cfg, 2, true), base, "one ray at a time");
}

/// Whether `(x, z)` lies off the checker squares' edges, where bilinear
/// filtering blends the two sides.
fn inside_a_square(x: f32, z: f32) -> bool {
    let frac = |c: f32| ((c + 2.0) * CHECKS as f32 / 4.0).fract();
    [frac(x), frac(z)].iter().all(|f| (0.05..0.95).contains(f))
}

#[test]
fn no_photon_is_stored_in_a_hole() {
    let scene = checkered("MASK");
    let device = Device::new().unwrap();
    let tracer = Tracer::new(Arc::new(scene.commit(&device).unwrap()));
    let mut cfg = TraceConfig::new(Mode::Classic, Budget::NMax(50_000));
    cfg.seed = 4;
    let records = tracer.trace(&cfg).unwrap().records();
    let on_plane: Vec<_> = records
        .iter()
        .filter(|r| (r.position.y - 1.0).abs() < 1e-3)
        .collect();
    assert!(on_plane.len() > 5_000, "{} on the plane", on_plane.len());
    for r in on_plane {
        let (x, z) = (r.position.x, r.position.z);
        if inside_a_square(x, z) {
            assert!(
                !checker_clear(x, z),
                "a photon stored in a hole at ({x}, {z})"
            );
        }
    }
}

#[test]
fn surface_points_leave_the_holes_out() {
    let hole = load(&fence_scene(Some(plane_material("MASK", 0.0, false)), None));
    let points = hole.surface_sampler().points(4000, 3);
    assert!(points.iter().all(|p| p.mesh != 2), "a point in the hole");
    assert!(
        points.len() > 1000 && points.len() < 4000,
        "{}",
        points.len()
    );
    let checker = checkered("MASK");
    let points = checker.surface_sampler().points(4000, 3);
    let on_plane: Vec<_> = points.iter().filter(|p| p.mesh == 2).collect();
    assert!(!on_plane.is_empty());
    for p in on_plane {
        let (x, z) = (p.position.x, p.position.z);
        if inside_a_square(x, z) {
            assert!(!checker_clear(x, z), "a point in a hole at ({x}, {z})");
        }
    }
}

/// The Cornell box with a fence across it at z = 200, in front of the light:
/// a white Lambert panel over the whole cross-section with an 8 x 8
/// checkerboard of holes, built through the library API.
pub(crate) fn cornell_with_fence() -> Scene {
    let mut s = Scene::cornell().unwrap();
    let sampler = Sampler {
        filter: Filter::Nearest,
        ..Sampler::default()
    };
    let tex = s.add_texture(Texture::new(8, 8, checker_texels(8), sampler).unwrap());
    let m = s.add_material(Material {
        name: "fence".into(),
        brdf: Brdf::Lambert(Lambert::new(Vec3::splat(0.7)).unwrap()),
        emission: None,
    });
    let (x1, y1, z) = (556.0, 548.0, 200.0);
    let p = vec![
        Vec3::new(0.0, 0.0, z),
        Vec3::new(x1, 0.0, z),
        Vec3::new(x1, y1, z),
        Vec3::new(0.0, y1, z),
    ];
    let mesh = s
        .add_mesh("fence", p, vec![[0, 1, 2], [0, 2, 3]], m)
        .unwrap();
    let uv = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    s.set_texcoords(mesh, 0, uv.iter().map(|&c| c.into()).collect())
        .unwrap();
    let texture = TextureRef {
        texture: tex,
        tex_coord: 0,
        transform: TexTransform::default(),
    };
    s.set_alpha_mask(m, AlphaMask::new(0.5, 1.0).with_texture(texture))
        .unwrap();
    s
}

#[test]
fn photon_and_path_renders_agree_through_a_fence() {
    let scene = cornell_with_fence();
    assert!(scene.has_holes());
    // Twice the Cornell box's runs: the fence's shadow makes the box darker
    // and its photon estimate noisier, and the check holds its bound under
    // 5 % of the mean.
    crate::path_tracer::assert_photon_and_path_agree(scene, 20);
}
