//! Emissive textures (`emissiveTexture`): an area light whose radiance is
//! `emissiveFactor * texel`, its power the sum over the texels it covers
//! (sRGB-decoded, through the sampler and the texture transform), its
//! photons placed by emitted power, and the photon tracer, the renderer's
//! light sampling and the path tracer all reading the same radiance.
//!
//! The lamp is a 1 x 1 square at y = 1 facing down, texture coordinates
//! `(0, 0)` at `(x, z) = (-0.5, -0.5)`, `u` along x and `v` along z; the
//! floor, when present, a 4 x 4 matte square at y = 0.

use crate::gltf_textures::png_rgb;
use adaptive_pm::embree::{thread_pool, Device, EmbreeScene};
use adaptive_pm::engine::{Budget, Mode, TraceConfig, TraceOutput, Tracer};
use adaptive_pm::photon_map::PhotonRecord;
use adaptive_pm::raycast::Ray;
use adaptive_pm::render::{
    light_pixels, render_with, unshadowed_irradiance, Image, LightSampler, PathHalves, PathPart,
    PathTracer, RenderConfig, View,
};
use adaptive_pm::rng::{hash2, Rng};
use adaptive_pm::sampling::luminance;
use adaptive_pm::scene::{AreaLight, Camera, Light, Scene};
use glam::Vec3;
use serde_json::{json, Value};
use std::f64::consts::PI;
use std::sync::Arc;

use crate::common;
use crate::gltf_doc::{square, Doc};

const NEAREST_CLAMP: &str = r#"{"magFilter": 9728, "wrapS": 33071, "wrapT": 33071}"#;
const LINEAR_CLAMP: &str = r#"{"magFilter": 9729, "wrapS": 33071, "wrapT": 33071}"#;
const NEAREST_MIRROR: &str = r#"{"magFilter": 9728, "wrapS": 33648, "wrapT": 33648}"#;
const LINEAR_REPEAT: &str = r#"{"magFilter": 9729}"#;
const FLOOR_ALBEDO: f64 = 0.5;

/// sRGB's decoding (IEC 61966-2-1), written out here as the oracle.
fn srgb(c: u8) -> f64 {
    let c = f64::from(c) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// A 4 x 4 texture of distinct greys and colours (texel `(i, j)` at `i + 4 j`).
fn sixteen() -> Vec<[u8; 3]> {
    (0..16u8)
        .map(|k| {
            [
                10 + 15 * k,
                250 - 13 * k,
                if k % 3 == 0 { 0 } else { 40 + 9 * k },
            ]
        })
        .collect()
}

/// The lamp (texture `png` through `sampler`, texture info `info`, factor
/// `factor`), and the floor when `floor`.
fn lamp_scene(tex: Option<(&[u8], &str)>, info: Value, factor: [f32; 3], floor: bool) -> Doc {
    let mut doc = Doc::default();
    if let Some((png, sampler)) = tex {
        doc.texture(png, serde_json::from_str(sampler).unwrap());
    }
    let mut lamp = json!({"name": "lamp", "emissiveFactor": factor,
        "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0}});
    if tex.is_some() {
        lamp["emissiveTexture"] = info;
    }
    let lamp = doc.material(lamp);
    let (p, i) = square(0.5, false);
    let l = doc.mesh(&p, &i, 4, Some(lamp));
    doc.texcoords(l, &[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
    doc.node(json!({"mesh": l, "translation": [0.0, 1.0, 0.0]}));
    if floor {
        let a = FLOOR_ALBEDO as f32;
        let m = doc.material(json!({"name": "floor", "pbrMetallicRoughness":
            {"baseColorFactor": [a, a, a, 1.0], "metallicFactor": 0.0}}));
        let (p, i) = square(2.0, true);
        let f = doc.mesh(&p, &i, 4, Some(m));
        doc.node(json!({ "mesh": f }));
    }
    if doc.materials[0]
        .get("emissiveTexture")
        .is_some_and(|t| t.get("extensions").is_some())
    {
        doc.extensions_used.push("KHR_texture_transform");
    }
    doc
}

fn load(doc: &Doc) -> Scene {
    let dir = tempfile::tempdir().unwrap();
    Scene::load(doc.write(dir.path())).unwrap()
}

fn lamp(scene: &Scene) -> &AreaLight {
    match &scene.lights()[0] {
        Light::Area(a) => a,
        other => panic!("the lamp is an area light, got {other:?}"),
    }
}

/// Relative difference of two powers, the worst channel.
fn rel(a: Vec3, b: [f64; 3]) -> f64 {
    (0..3)
        .map(|c| (f64::from(a[c]) - b[c]).abs() / b[c].abs().max(1e-30))
        .fold(0.0, f64::max)
}

/// `pi * factor * sum_texels (weight * decoded texel) * (world area per uv
/// area)`: a one-sided diffuse lamp's power.
fn hand_power(
    factor: [f64; 3],
    texels: &[[u8; 3]],
    weights: &[f64],
    world_per_uv: f64,
) -> [f64; 3] {
    let mut p = [0.0; 3];
    for (t, w) in texels.iter().zip(weights) {
        for c in 0..3 {
            p[c] += w * srgb(t[c]);
        }
    }
    std::array::from_fn(|c| PI * factor[c] * p[c] * world_per_uv)
}

#[test]
fn the_power_is_the_sum_over_the_texels() {
    let texels = sixteen();
    let png = png_rgb(4, 4, &texels);
    let f = [0.9, 0.6, 0.3];
    let f64s = f.map(f64::from);
    // The whole texture once: each texel a sixteenth of the unit square.
    let s = load(&lamp_scene(
        Some((&png, NEAREST_CLAMP)),
        json!({"index": 0}),
        f,
        false,
    ));
    let want = hand_power(f64s, &texels, &[1.0 / 16.0; 16], 1.0);
    let got = s.lights()[0].power();
    assert!(lamp(&s).is_textured() && lamp(&s).power_is_exact());
    assert!(rel(got, want) < 1e-5, "{got} vs {want:?}");
    // Bilinear with CLAMP_TO_EDGE over exactly the image integrates to the
    // texels' mean too (the half-texel borders hold the edge values).
    let s = load(&lamp_scene(
        Some((&png, LINEAR_CLAMP)),
        json!({"index": 0}),
        f,
        false,
    ));
    assert!(rel(s.lights()[0].power(), want) < 1e-5);
    // Scale 0.5: the lamp covers the top-left 2 x 2 texels only, each now
    // a quarter of it.
    let info = json!({"index": 0, "extensions": {"KHR_texture_transform": {"scale": [0.5, 0.5]}}});
    let s = load(&lamp_scene(Some((&png, NEAREST_CLAMP)), info, f, false));
    let w: Vec<f64> = (0..16)
        .map(|k| if k % 4 < 2 && k / 4 < 2 { 0.0625 } else { 0.0 })
        .collect();
    let want = hand_power(f64s, &texels, &w, 4.0);
    assert!(
        rel(s.lights()[0].power(), want) < 1e-5,
        "{} vs {want:?}",
        s.lights()[0].power()
    );
    // MIRRORED_REPEAT with u scaled by 1.5: the columns 0..3, then 3 and 2
    // again; the uv area 1.5 over a world area of 1.
    let info = json!({"index": 0, "extensions": {"KHR_texture_transform": {"scale": [1.5, 1.0]}}});
    let s = load(&lamp_scene(Some((&png, NEAREST_MIRROR)), info, f, false));
    let w: Vec<f64> = (0..16)
        .map(|k| if k % 4 >= 2 { 2.0 / 16.0 } else { 1.0 / 16.0 })
        .collect();
    let want = hand_power(f64s, &texels, &w, 1.0 / 1.5);
    assert!(
        rel(s.lights()[0].power(), want) < 1e-5,
        "{} vs {want:?}",
        s.lights()[0].power()
    );
    // KHR_materials_emissive_strength scales it.
    let mut doc = lamp_scene(Some((&png, NEAREST_CLAMP)), json!({"index": 0}), f, false);
    doc.materials[0]["extensions"] =
        json!({"KHR_materials_emissive_strength": {"emissiveStrength": 3.0}});
    doc.extensions_used.push("KHR_materials_emissive_strength");
    let want = hand_power(f64s.map(|c| 3.0 * c), &texels, &[1.0 / 16.0; 16], 1.0);
    assert!(rel(load(&doc).lights()[0].power(), want) < 1e-5);
}

/// A rotated, offset, repeated bilinear texture against the test's own
/// brute-force midpoint sum of the sampled radiance over a 1500^2 grid in
/// world space (its error falls as h^2: measured 1.7e-6 relative at 750^2,
/// 4e-7 at 1500^2; the bound, 2e-5, is far below what a misplaced cell or a
/// wrong filter gives, ~1e-2).
#[test]
fn a_rotated_bilinear_texture_integrates_as_a_fine_midpoint_sum() {
    let png = png_rgb(4, 4, &sixteen());
    let info = json!({"index": 0, "extensions": {"KHR_texture_transform":
        {"offset": [0.3, -0.2], "rotation": 0.7, "scale": [1.7, 2.3]}}});
    let s = load(&lamp_scene(
        Some((&png, LINEAR_REPEAT)),
        info,
        [1.0, 1.0, 1.0],
        false,
    ));
    let light = lamp(&s);
    assert!(light.power_is_exact() && light.piece_count() > 16);
    let n = 1500;
    let mut sum = [0.0f64; 3];
    // The square's two triangles, [0, 1, 2] and [0, 2, 3]: a point at
    // (x, z) lies in the first when x >= z (in the lamp's coordinates).
    for a in 0..n {
        for b in 0..n {
            let (u, v) = ((a as f32 + 0.5) / n as f32, (b as f32 + 0.5) / n as f32);
            // Square corners p0 (0, 0), p1 (1, 0), p2 (1, 1), p3 (0, 1) in (u, v).
            let l = if u >= v {
                light.radiance_at(0, u - v, v)
            } else {
                light.radiance_at(1, u, v - u)
            };
            for c in 0..3 {
                sum[c] += f64::from(l[c]);
            }
        }
    }
    let want = sum.map(|x| x * PI / (n * n) as f64);
    let got = light.power();
    assert!(rel(got, want) < 2e-5, "{got} vs {want:?}");
}

/// Photon origins over 400k photons of a nearest-filtered 4 x 4 lamp (one
/// texel black): per texel, the count within 4 sigma (binomial, and
/// Bonferroni over the 16: `family_bound`) of `N P_texel / P` (by
/// luminance), every photon of the mean luminance (the sampler follows the
/// power exactly), none from the black
/// texel; a bilinear lamp's weighted sums per texel within their own
/// measured noise of the texel's power.
#[test]
fn photons_leave_each_texel_in_proportion_to_its_power() {
    let mut texels = sixteen();
    texels[5] = [0, 0, 0];
    let png = png_rgb(4, 4, &texels);
    let f = [1.0, 0.8, 0.6];
    let n = 400_000u32;
    let bound = common::family_bound(16, u64::from(n), 1e-4).max(4.0);
    for sampler in [NEAREST_CLAMP, LINEAR_CLAMP] {
        let s = load(&lamp_scene(
            Some((&png, sampler)),
            json!({"index": 0}),
            f,
            false,
        ));
        let light = &s.lights()[0];
        let power = light.power();
        let mut rng = Rng::new(common::seed(11));
        let mut counts = [0u32; 16];
        let mut inside_black = 0u32;
        let mut weighted = [[0.0f64; 2]; 16];
        for _ in 0..n {
            let e = light.sample(rng.next_f32(), rng.next_2d(), rng.next_2d());
            assert!(e.direction.y < 0.0, "a one-sided lamp facing down");
            let (u, v) = (e.origin.x + 0.5, e.origin.z + 0.5);
            let k = (u * 4.0).floor().clamp(0.0, 3.0) as usize
                + 4 * (v * 4.0).floor().clamp(0.0, 3.0) as usize;
            counts[k] += 1;
            // A point within rounding of a texel line may bin either side.
            let off_lines = |x: f32| ((x * 4.0) - (x * 4.0).round()).abs() > 1e-4;
            inside_black += u32::from(k == 5 && off_lines(u) && off_lines(v));
            let w = f64::from(e.weight.x * power.x) / f64::from(n);
            weighted[k][0] += w;
            weighted[k][1] += w * w;
            if sampler == NEAREST_CLAMP {
                // Drawn by luminance: every photon carries the mean luminance.
                let y = luminance(e.weight * power) / luminance(power);
                assert!((y - 1.0).abs() < 1e-4, "{}: luminance ratio {y}", e.weight);
            }
        }
        let texel_luminance = |k: usize| {
            let p = hand_power(f.map(f64::from), &texels[k..=k], &[1.0 / 16.0], 1.0);
            f64::from(luminance(Vec3::from(p.map(|c| c as f32))))
        };
        if sampler == NEAREST_CLAMP {
            assert_eq!(inside_black, 0, "the black texel emits no photon");
            assert!(
                counts[5] <= 2,
                "{} photons on the black texel's edges",
                counts[5]
            );
            let total: f64 = (0..16).map(texel_luminance).sum();
            let (k, z) = (0..16)
                .map(|k| {
                    let p = texel_luminance(k) / total;
                    let sd = (f64::from(n) * p * (1.0 - p)).sqrt().max(1.0);
                    (k, (f64::from(counts[k]) - f64::from(n) * p) / sd)
                })
                .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
                .unwrap();
            eprintln!("nearest: the worst texel {k} is {z:+.2} sigma off its share");
            common::assert_sigmas("worst texel's photon count", z, 1.0, bound);
        } else {
            // Bilinear: the texel squares' powers by a fine midpoint sum of the
            // light's radiance (the oracle), against the photons' weighted sums.
            let light = lamp(&s);
            let m = 200;
            let (k, dev, se) = (0..16)
                .map(|k| {
                    let (i, j) = (k % 4, k / 4);
                    let mut e = 0.0;
                    for a in 0..m {
                        for b in 0..m {
                            let u = (i as f32 + (a as f32 + 0.5) / m as f32) / 4.0;
                            let v = (j as f32 + (b as f32 + 0.5) / m as f32) / 4.0;
                            let l = if u >= v {
                                light.radiance_at(0, u - v, v)
                            } else {
                                light.radiance_at(1, u, v - u)
                            };
                            e += f64::from(l.x);
                        }
                    }
                    let want = e * PI / 16.0 / (m * m) as f64;
                    let [s1, s2] = weighted[k];
                    let se = (s2 - s1 * s1 / f64::from(n)).max(0.0).sqrt();
                    (k, s1 - want, se)
                })
                .max_by(|a, b| (a.1 / a.2).abs().total_cmp(&(b.1 / b.2).abs()))
                .unwrap();
            eprintln!("bilinear: the worst texel {k} is off by {dev:+.3e} +- {se:.3e}");
            common::assert_sigmas("worst texel's weighted power", dev, se, bound);
        }
    }
}

fn trace(prepared: &Arc<EmbreeScene>, n_max: u64, seed: u64) -> TraceOutput {
    let mut cfg = TraceConfig::new(Mode::Classic, Budget::NMax(n_max));
    cfg.seed = seed;
    Tracer::new(Arc::clone(prepared)).trace(&cfg).unwrap()
}

/// First hits on the floor (y = 0) of a fresh trace.
fn floor_hits(scene: &Scene, n_max: u64, seed: u64) -> Vec<PhotonRecord> {
    let device = Device::new().unwrap();
    let prepared = Arc::new(scene.clone().commit(&device).unwrap());
    trace(&prepared, n_max, seed)
        .records()
        .into_iter()
        .filter(|r| r.depth == 0 && r.position.y.abs() < 1e-3)
        .collect()
}

/// The red power of `hits` where `keep` says, and its standard error (a
/// sum of independent photons: the root of the sum of squares).
fn flux(hits: &[PhotonRecord], keep: impl Fn(Vec3) -> bool) -> (f64, f64) {
    let p: Vec<f64> = hits
        .iter()
        .filter(|r| keep(r.position))
        .map(|r| f64::from(r.power.x))
        .collect();
    (p.iter().sum(), p.iter().map(|x| x * x).sum::<f64>().sqrt())
}

/// Over a centred square floor, any 2 x 2 texture gives the flux of its
/// mean as a flat factor: each lamp quadrant sends the floor the same share
/// (the floor's four-fold symmetry), so `sum_q L_q share = share sum_q L_q`.
/// Both fluxes within 4 of their measured standard errors; the texture is
/// read (a texture 1.6x brighter than its mean's half would differ by far
/// more than the noise: checked against the factor alone).
#[test]
fn a_textured_lamp_lights_the_floor_like_its_mean_as_a_flat_factor() {
    let texels = [[255, 40, 0], [30, 200, 90], [120, 120, 255], [0, 0, 0]];
    let png = png_rgb(2, 2, &texels);
    let textured = load(&lamp_scene(
        Some((&png, NEAREST_CLAMP)),
        json!({"index": 0}),
        [1.0; 3],
        true,
    ));
    let mean = texels.iter().map(|t| srgb(t[0])).sum::<f64>() / 4.0;
    let flat = load(&lamp_scene(None, Value::Null, [mean as f32; 3], true));
    let factor_only = load(&lamp_scene(None, Value::Null, [1.0; 3], true));
    let all = |_: Vec3| true;
    let (t, t_se) = flux(&floor_hits(&textured, 200_000, common::seed(21)), all);
    let (f, f_se) = flux(&floor_hits(&flat, 200_000, common::seed(22)), all);
    let (o, o_se) = flux(&floor_hits(&factor_only, 200_000, common::seed(23)), all);
    eprintln!(
        "floor flux: textured {t:.5} +- {t_se:.5}, flat mean {f:.5} +- {f_se:.5}, factor {o:.5}"
    );
    let se = t_se.hypot(f_se);
    common::assert_sigmas("textured vs flat mean floor flux", t - f, se, 4.0);
    let se = t_se.hypot(mean * o_se);
    common::assert_sigmas("textured vs factor times mean", t - mean * o, se, 4.0);
    assert!(
        (o - t).abs() > 10.0 * o_se.hypot(t_se),
        "the texture is read"
    );
}

/// A lamp bright on its -x half only: the floor's -x half gets more than its
/// +x half, by the ratio the unshadowed quadrature of the textured light
/// gives (integrated over each half on a 40 x 80 grid of points, the lamp
/// on a 16-grid per triangle: 1.5e-4 relative off a 80 x 160 grid with a
/// 64-grid lamp, measured, a twentieth of the photons' sigma); each half's
/// flux within 4 sigma of it.
#[test]
fn a_lamp_bright_on_one_half_lights_the_floor_under_it() {
    let png = png_rgb(2, 1, &[[255, 255, 255], [0, 0, 0]]);
    let s = load(&lamp_scene(
        Some((&png, NEAREST_CLAMP)),
        json!({"index": 0}),
        [1.0; 3],
        true,
    ));
    let hits = floor_hits(&s, 200_000, common::seed(24));
    let quad = |x0: f32| {
        let (nx, nz) = (40, 80);
        let mut e = 0.0;
        for a in 0..nx {
            for b in 0..nz {
                let x = x0 + 2.0 * (a as f32 + 0.5) / nx as f32;
                let z = -2.0 + 4.0 * (b as f32 + 0.5) / nz as f32;
                e += f64::from(unshadowed_irradiance(&s, Vec3::new(x, 0.0, z), Vec3::Y, 16).x);
            }
        }
        e * 8.0 / (nx * nz) as f64
    };
    let (want_left, want_right) = (quad(-2.0), quad(0.0));
    let (left, l_se) = flux(&hits, |p| p.x < 0.0);
    let (right, r_se) = flux(&hits, |p| p.x >= 0.0);
    eprintln!("-x half {left:.5} +- {l_se:.5} (quadrature {want_left:.5}), +x half {right:.5} +- {r_se:.5} ({want_right:.5})");
    assert!(want_left > 1.5 * want_right);
    common::assert_sigmas("the bright half's floor flux", left - want_left, l_se, 4.0);
    common::assert_sigmas("the dark half's floor flux", right - want_right, r_se, 4.0);
}

/// The photon tracer's first-hit flux into each of the floor's 4 x 4 cells
/// against the path tracer's direct light integrated over the cell (at
/// uniform random points: `E = pi L / albedo`), and the photon renderer's
/// light sampling likewise: all unbiased, so each cell's difference within
/// the family bound of the 16 cells' measured sigmas. A bilinear texture,
/// rotated, and a two-sided lamp with a cos^2 profile (`--cosn`).
#[test]
fn the_photon_tracer_the_renderer_and_the_path_tracer_agree() {
    let png = png_rgb(4, 4, &sixteen());
    let info = json!({"index": 0, "extensions": {"KHR_texture_transform": {"rotation": 0.4, "scale": [1.3, 1.0]}}});
    let mut doc = lamp_scene(Some((&png, LINEAR_REPEAT)), info, [1.0; 3], true);
    doc.materials[0]["doubleSided"] = json!(true);
    let mut scene = load(&doc);
    scene.set_cosn(adaptive_pm::emitter::CosN::new(2.0).unwrap());
    let hits = floor_hits(&scene, 300_000, common::seed(25));
    let device = Device::new().unwrap();
    let prepared = scene.clone().commit(&device).unwrap();
    let paths = PathTracer::new(&prepared);
    let lights = LightSampler::new(&prepared);
    let brdf = scene.materials()[scene.meshes()[1].material].brdf;
    let eps = scene.ray_epsilon();
    let points = 400u64;
    let bound = common::family_bound(32, points - 1, 1e-4);
    let mut worst: Option<(String, f64, f64)> = None;
    for cell in 0..16u64 {
        let (x0, z0) = (-2.0 + (cell % 4) as f32, -2.0 + (cell / 4) as f32);
        let (photons, p_se) = flux(&hits, |p| {
            p.x >= x0 && p.x < x0 + 1.0 && p.z >= z0 && p.z < z0 + 1.0
        });
        let mut rng = Rng::new(hash2(common::seed(26), cell));
        let (mut by_path, mut by_lights) = (common::MeanVar::default(), common::MeanVar::default());
        for _ in 0..points {
            let [a, b] = rng.next_2d();
            let x = Vec3::new(x0 + a, 0.0, z0 + b);
            let ray = Ray::new(x + Vec3::Y * 0.01, -Vec3::Y);
            let l = paths.radiance(ray, PathPart::Direct, false, &mut rng).x;
            by_path.push(f64::from(l) * PI / FLOOR_ALBEDO);
            let l = lights
                .sample(&brdf, [x, Vec3::Y, Vec3::Y, Vec3::Y], eps, rng.next_2d())
                .x;
            by_lights.push(f64::from(l) * PI / FLOOR_ALBEDO);
        }
        for (name, m) in [("path tracer", by_path), ("light sampling", by_lights)] {
            let (dev, se) = (photons - m.mean(), p_se.hypot(m.std_error()));
            if worst
                .as_ref()
                .is_none_or(|w| (dev / se).abs() > (w.1 / w.2).abs())
            {
                worst = Some((format!("cell {cell}: photons vs {name}"), dev, se));
            }
        }
    }
    let (what, dev, se) = worst.unwrap();
    eprintln!("{what} is the worst: {dev:+.4e} +- {se:.4e}");
    common::assert_sigmas(&what, dev, se, bound);
}

/// A camera or gather ray that hits the lamp sees the texel there times
/// the factor, in the renderer (`Scene::emitted_radiance`) and in the path
/// tracer (the emitter seen from the camera).
#[test]
fn a_ray_that_hits_the_lamp_sees_its_texel() {
    let png = png_rgb(
        2,
        2,
        &[[255, 40, 0], [30, 200, 90], [120, 120, 255], [0, 0, 0]],
    );
    let f = [1.0, 0.6, 0.4];
    let s = load(&lamp_scene(
        Some((&png, NEAREST_CLAMP)),
        json!({"index": 0}),
        f,
        false,
    ));
    let device = Device::new().unwrap();
    let prepared = s.clone().commit(&device).unwrap();
    let paths = PathTracer::new(&prepared);
    for (x, z, texel) in [
        (-0.25, -0.25, [255, 40, 0]),
        (0.25, -0.25, [30, 200, 90]),
        (-0.25, 0.25, [120, 120, 255]),
        (0.25, 0.25, [0, 0, 0]),
    ] {
        let want = Vec3::from(std::array::from_fn::<f32, 3, _>(|c| {
            (f64::from(f[c]) * srgb(texel[c])) as f32
        }));
        let ray = Ray::new(Vec3::new(x, 0.0, z), Vec3::Y);
        let hit = prepared
            .caster()
            .intersect(&ray)
            .expect("the lamp is above");
        let got = s.emitted_radiance(&hit, -Vec3::Y);
        assert!((got - want).abs().max_element() < 1e-5, "{got} vs {want}");
        assert_eq!(
            s.emitted_radiance(&hit, Vec3::Y),
            Vec3::ZERO,
            "the back is dark"
        );
        let seen = paths.radiance(ray, PathPart::Full, true, &mut Rng::new(1));
        assert!(
            (seen - want).abs().max_element() < 1e-5,
            "path tracer {seen} vs {want}"
        );
    }
}

/// The same seed gives the same photon map on one thread or two.
#[test]
fn a_textured_lamp_traces_deterministically() {
    let png = png_rgb(4, 4, &sixteen());
    let s = load(&lamp_scene(
        Some((&png, LINEAR_REPEAT)),
        json!({"index": 0}),
        [1.0; 3],
        true,
    ));
    let device = Device::new().unwrap();
    let prepared = Arc::new(s.commit(&device).unwrap());
    let checksum = |out: TraceOutput| out.into_map().checksum();
    let want = checksum(trace(&prepared, 20_000, 7));
    for threads in [1, 2] {
        let pool = thread_pool(threads).unwrap();
        assert_eq!(
            checksum(pool.install(|| trace(&prepared, 20_000, 7))),
            want,
            "{threads} threads"
        );
    }
    assert_ne!(checksum(trace(&prepared, 20_000, 8)), want);
}

/// A black texture or a zero factor makes no light, with a warning; a lamp
/// without the texture coordinates its texture reads is refused by name.
#[test]
fn dark_and_broken_emissive_textures() {
    let black = png_rgb(2, 2, &[[0, 0, 0]; 4]);
    let mut doc = lamp_scene(
        Some((&black, NEAREST_CLAMP)),
        json!({"index": 0}),
        [1.0; 3],
        true,
    );
    // A second lamp, untextured, so the scene still has a light.
    let other = doc.material(json!({"name": "other", "emissiveFactor": [1.0, 1.0, 1.0]}));
    let (p, i) = square(0.1, false);
    let m = doc.mesh(&p, &i, 4, Some(other));
    doc.node(json!({"mesh": m, "translation": [0.0, 1.5, 0.0]}));
    let s = load(&doc);
    assert_eq!(s.lights().len(), 1, "the black lamp is no light");
    assert!(
        s.warnings()
            .join("\n")
            .contains("emissiveTexture is black in every texel"),
        "{:?}",
        s.warnings()
    );
    let png = png_rgb(2, 2, &sixteen()[..4]);
    let mut doc = lamp_scene(
        Some((&png, NEAREST_CLAMP)),
        json!({"index": 0}),
        [0.0; 3],
        true,
    );
    let other = other_material(&mut doc);
    let m = doc.mesh(&p, &i, 4, Some(other));
    doc.node(json!({"mesh": m, "translation": [0.0, 1.5, 0.0]}));
    let s = load(&doc);
    assert_eq!(s.lights().len(), 1);
    assert!(s.warnings().join("\n").contains("emissiveFactor of zero"));
    // A texture bright elsewhere, the lamp covering its black texel only
    // (scale 0.5: the top-left quarter): a light of no power, and a warning.
    let png = png_rgb(2, 2, &[[0, 0, 0], [255; 3], [255; 3], [255; 3]]);
    let info = json!({"index": 0, "extensions": {"KHR_texture_transform": {"scale": [0.5, 0.5]}}});
    let mut doc = lamp_scene(Some((&png, NEAREST_CLAMP)), info, [1.0; 3], true);
    let other = other_material(&mut doc);
    let m = doc.mesh(&p, &i, 4, Some(other));
    doc.node(json!({"mesh": m, "translation": [0.0, 1.5, 0.0]}));
    let s = load(&doc);
    assert_eq!(s.lights()[0].power(), Vec3::ZERO);
    assert!(s.lights()[1].power().x > 0.0);
    assert!(
        s.warnings().join("\n").contains("that it covers is black"),
        "{:?}",
        s.warnings()
    );
    let png = png_rgb(2, 2, &sixteen()[..4]);
    let doc = lamp_scene(
        Some((&png, NEAREST_CLAMP)),
        json!({"index": 0, "texCoord": 1}),
        [1.0; 3],
        true,
    );
    let dir = tempfile::tempdir().unwrap();
    let e = Scene::load(doc.write(dir.path())).unwrap_err().to_string();
    assert!(e.contains("no TEXCOORD_1"), "{e}");
}

fn other_material(doc: &mut Doc) -> usize {
    doc.material(json!({"name": "other", "emissiveFactor": [1.0, 1.0, 1.0]}))
}

/// Mean over the kept pixels, and the standard error of the mean of two
/// independent renders from their pixel-by-pixel differences (channel mean).
fn pair_mean_se(a: &Image, b: &Image, keep: &[bool]) -> (f64, f64) {
    let (mut sum, mut sq, mut n) = (0.0, 0.0, 0.0);
    for ((p, q), _) in a
        .pixels
        .iter()
        .zip(&b.pixels)
        .zip(keep)
        .filter(|(_, k)| **k)
    {
        let (p, q) = (
            p.as_dvec3().element_sum() / 3.0,
            q.as_dvec3().element_sum() / 3.0,
        );
        sum += 0.5 * (p + q);
        sq += (0.5 * (p - q)).powi(2);
        n += 1.0;
    }
    (sum / n, sq.sqrt() / n)
}

/// The photon renderer's direct light (`View::DirectOnly`: its stratified
/// light samples, the piece from the light pair and the point in it from
/// its own pair) and the path tracer's direct part, over a 24 x 24 image
/// of the floor under a textured lamp: both unbiased, their means over
/// the non-light pixels within 4 sigma of the noise measured from two
/// independent renders of each.
#[test]
fn the_renderers_direct_light_matches_the_path_tracers_image() {
    let png = png_rgb(4, 4, &sixteen());
    let info = json!({"index": 0, "extensions": {"KHR_texture_transform": {"rotation": 0.4}}});
    let s = load(&lamp_scene(
        Some((&png, LINEAR_REPEAT)),
        info,
        [1.0; 3],
        true,
    ));
    let device = Device::new().unwrap();
    let prepared = s.commit(&device).unwrap();
    let mut cfg = RenderConfig::new(24, 24);
    cfg.camera =
        Some(Camera::look_at(Vec3::new(0.0, 0.6, 2.6), Vec3::ZERO, Vec3::Y, 60.0).unwrap());
    cfg.spp = 32;
    cfg.show_emitters = false;
    cfg.view = View::DirectOnly;
    cfg.seed = common::seed(27);
    let keep: Vec<bool> = light_pixels(&prepared, &cfg)
        .unwrap()
        .iter()
        .map(|l| !l)
        .collect();
    let photon = |seed| {
        let cfg = RenderConfig {
            seed,
            ..cfg.clone()
        };
        render_with(&prepared, None, None, &cfg, &|_, _| {})
            .unwrap()
            .0
    };
    let (a, b) = (photon(cfg.seed), photon(hash2(cfg.seed, 1)));
    let (m_photon, se_photon) = pair_mean_se(&a, &b, &keep);
    let halves = PathHalves::render(&prepared, &cfg, PathPart::Direct).unwrap();
    let (m_path, se_path) = pair_mean_se(&halves.a, &halves.b, &keep);
    eprintln!("direct light: renderer {m_photon:.5} +- {se_photon:.5}, path tracer {m_path:.5} +- {se_path:.5}");
    assert!(
        m_path > 50.0 * se_path,
        "the floor is lit, far above the noise"
    );
    common::assert_sigmas(
        "renderer vs path tracer direct light",
        m_photon - m_path,
        se_photon.hypot(se_path),
        4.0,
    );
}
