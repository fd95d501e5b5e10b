//! The irradiance cache against the k-nearest estimate it replaces, the
//! render's new JSON keys, and clear errors for bad values of the new options.
//! Small budgets and tiny images, fixed seeds.

use adaptive_pm::embree::Device;
use adaptive_pm::engine::{Budget, Maps, Mode, TraceConfig, Tracer};
use adaptive_pm::photon_map::{PhotonMap, PhotonRecord};
use adaptive_pm::render::{
    cache::MAX_STRIDE, default_max_radius, floor_points, irradiance_estimate, render, CacheConfig,
    IrradianceCache, Lookup, RenderConfig, View,
};
use adaptive_pm::rng::Rng;
use adaptive_pm::scene::{triangle_area, PreparedScene, Scene};
use adaptive_pm::Error;
use glam::Vec3;
use serde_json::Value;
use std::process::Command;

/// On the Cornell floor (points kept 10 % away from the walls, none under the
/// blocks), the cache's irradiance equals the k-nearest estimate at the query
/// point within the cache's interpolation error. A cell (side `h = 1.0 r`)
/// holds an estimate at one of its samples, at most `h sqrt(3)` from the
/// query, from the 7/8 of the photons that are not samples. The cone
/// estimate's relative variance for a uniform density is `1 / (2 (k - 1))`
/// from the weights plus `1 / (k - 2)` from the radius, `sigma = 12.3 %` at
/// k = 100; two such estimates differ by at most `sigma sqrt(2)` = 17.4 % RMS
/// when they share no photon (they share some), plus the change of the
/// irradiance over a fraction of a kernel radius. Stated bound: 18 % RMS
/// over the points, 2 % on the mean (the shift has no preferred direction).
#[test]
fn cache_matches_the_knn_estimate_on_the_cornell_floor() {
    let scene = Scene::cornell().unwrap();
    let device = Device::new().unwrap();
    let rt = scene.embree_geometry(&device).unwrap();
    let mut cfg = TraceConfig::new(Mode::Classic, Budget::NMax(300_000));
    cfg.seed = 5;
    let out = Tracer::new(PreparedScene::new(scene.clone(), &rt).unwrap())
        .trace(&cfg)
        .unwrap();
    let maps = Maps::build(&out.records());
    let lookup = Lookup {
        k: 100,
        max_radius: default_max_radius(&scene),
    };
    let (lo, hi) = scene.bounds();
    let cache_cfg = CacheConfig { stride: 8, lookup };
    let cache = IrradianceCache::build(&maps.full, &rt, (hi - lo).length(), &cache_cfg).unwrap();
    assert!(cache.bytes_per_entry() <= 16, "{}", cache.bytes_per_entry());
    let samples_per_photon = cache.samples() as f64 / maps.full.len() as f64;
    assert!(
        (samples_per_photon - 1.0 / 8.0).abs() < 0.01,
        "{samples_per_photon}"
    );
    assert!(cache.len() > 100 && cache.len() <= cache.samples());

    let pts = floor_points(&scene, "floor", 12, 12, 0.1);
    assert!(pts.len() > 100);
    let mut scratch = Vec::new();
    let (mut sum_c, mut sum_k, mut se, mut n) = (0.0f64, 0.0f64, 0.0f64, 0usize);
    for p in &pts {
        // Points inside a block (the floor under it) are never seen: their
        // upward ray meets the block's top, not the ceiling.
        let up = adaptive_pm::embree::Ray::new(p.position + p.normal * 0.01, p.normal);
        if rt.intersect(&up).is_none_or(|h| h.t < 500.0) {
            continue;
        }
        let knn = irradiance_estimate(&maps.full, p.position, p.normal, lookup, &mut scratch).value;
        let c = cache
            .irradiance(p.position, p.normal, [0.5; 3])
            .expect("every floor point is covered");
        let (c, k) = (c.x as f64, knn.x as f64);
        if k <= 0.0 {
            continue;
        }
        sum_c += c;
        sum_k += k;
        se += (c / k - 1.0).powi(2);
        n += 1;
    }
    let rms = (se / n as f64).sqrt();
    let mean = sum_c / sum_k - 1.0;
    eprintln!("cache vs k-NN on {n} floor points: RMS {rms:.4}, mean {mean:+.4}");
    assert!(rms < 0.18, "RMS relative difference {rms}");
    assert!(mean.abs() < 0.02, "mean relative difference {mean}");
}

/// Photons spread evenly over the Cornell floor, each of power 1: the exact
/// irradiance is `N / area`, and the cache, read at points over the floor's
/// middle, must give it within 0.5 % (the noise of the mean over ~8000
/// cells of 12 % each is ~0.15 %). Its two former biases fail this by far:
/// an estimate at a sample that counted the sample's own photon read
/// `(k + 1) / (k - 2)` = +3 %, and one that left it out but counted the other
/// samples read -1.5 % (a cell kept for its samples has, per cell, fewer of
/// them near its point than an independent point sees).
#[test]
fn cache_is_unbiased_on_a_uniform_density() {
    let scene = Scene::cornell().unwrap();
    let device = Device::new().unwrap();
    let rt = scene.embree_geometry(&device).unwrap();
    let floor: Vec<[Vec3; 3]> = scene
        .meshes()
        .iter()
        .filter(|m| m.name.starts_with("floor"))
        .flat_map(|m| (0..m.indices.len()).map(|i| m.triangle(i)))
        .collect();
    let areas: Vec<f32> = floor.iter().map(|&t| triangle_area(t)).collect();
    let area: f32 = areas.iter().sum();
    let n = 400_000;
    let mut rng = Rng::new(7);
    let records: Vec<PhotonRecord> = (0..n)
        .map(|_| {
            let mut pick = rng.next_f32() * area;
            let t = areas
                .iter()
                .position(|&a| {
                    pick -= a;
                    pick < 0.0
                })
                .unwrap_or(floor.len() - 1);
            let [u, v] = rng.next_2d();
            let (u, v) = if u + v > 1.0 {
                (1.0 - u, 1.0 - v)
            } else {
                (u, v)
            };
            let [a, b, c] = floor[t];
            PhotonRecord {
                position: a + (b - a) * u + (c - a) * v,
                power: Vec3::ONE,
                direction: -Vec3::Y,
                depth: 0,
            }
        })
        .collect();
    let map = PhotonMap::build(&records);
    let lookup = Lookup {
        k: 100,
        max_radius: default_max_radius(&scene),
    };
    let (lo, hi) = scene.bounds();
    let cache_cfg = CacheConfig { stride: 8, lookup };
    let cache = IrradianceCache::build(&map, &rt, (hi - lo).length(), &cache_cfg).unwrap();
    let exact = n as f64 / area as f64;
    let (mut sum, mut count) = (0.0f64, 0usize);
    for p in floor_points(&scene, "floor", 100, 100, 0.15) {
        for _ in 0..8 {
            let u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
            sum += cache.irradiance(p.position, Vec3::Y, u).unwrap().x as f64;
            count += 1;
        }
    }
    let mean = sum / count as f64 / exact - 1.0;
    eprintln!("cache / exact irradiance - 1 = {mean:+.4} over {count} lookups");
    assert!(mean.abs() < 0.005, "cache mean off by {mean:+.4}");
}

#[test]
fn bad_values_of_the_new_options_are_clear_errors() {
    let check = |cfg: RenderConfig, word: &str| match cfg.validate() {
        Err(Error::InvalidParameter { name, reason }) => {
            assert!(name.contains(word), "{name}: {reason}");
        }
        other => panic!("{word}: {other:?}"),
    };
    let mut c = RenderConfig::new(4, 4);
    c.light_samples = 0;
    check(c.clone(), "light samples");
    c.light_samples = 1;
    c.cache_stride = MAX_STRIDE + 1;
    check(c.clone(), "cache stride");
    // One sample per photon would leave no photon for the estimates.
    c.cache_stride = 1;
    check(c.clone(), "cache stride");
    c.cache_stride = 8;
    c.final_gather = 1 << 20;
    check(c.clone(), "final gather");
    c.final_gather = 1;
    c.max_radius = Some(-1.0);
    check(c, "max radius");
    let lookup = Lookup {
        k: 10,
        max_radius: 1.0,
    };
    assert!(CacheConfig { stride: 0, lookup }.validate().is_err());
    assert!(CacheConfig { stride: 1, lookup }.validate().is_err());
    assert!(CacheConfig { stride: 2, lookup }.validate().is_ok());

    // The CLI says which option and what it accepts.
    for (flag, value, word) in [
        ("--cache-stride", "1000000", "cache stride"),
        ("--cache-stride", "1", "cache stride"),
        ("--light-samples", "0", "light samples"),
        ("--final-gather", "99999", "final gather"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("x.exr");
        let o = Command::new(env!("CARGO_BIN_EXE_adaptive-pm"))
            .args([
                "render", "cornell", "--width", "4", "--height", "4", flag, value,
            ])
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(word), "{flag}: {err}");
        assert!(!err.contains("panicked"), "{err}");
        assert!(!out.exists());
    }
}

#[test]
fn render_json_has_the_throughput_keys() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.exr");
    let o = Command::new(env!("CARGO_BIN_EXE_adaptive-pm"))
        .args([
            "render", "cornell", "--n-max", "5000", "--width", "8", "--height", "8",
        ])
        .args(["--spp", "2", "--json", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    for key in ["samples_per_s", "lookup_s", "cache_build_s"] {
        let x = v[key]
            .as_f64()
            .unwrap_or_else(|| panic!("no number `{key}` in {v}"));
        assert!(x.is_finite() && x >= 0.0, "{key} = {x}");
    }
    assert!(v["samples_per_s"].as_f64().unwrap() > 0.0);
    assert!(v["cache_entries"].as_u64().unwrap() > 0);
    assert!(v["cache_bytes_per_entry"].as_u64().unwrap() <= 16);
}

/// The gather through the cache and the one through the full map's k-NN
/// estimate agree on the image's mean (the cache only moves where the
/// estimate is read), and the default render has no NaN.
#[test]
fn gather_through_the_cache_keeps_the_mean() {
    let scene = Scene::cornell().unwrap();
    let device = Device::new().unwrap();
    let rt = scene.embree_geometry(&device).unwrap();
    let mut t = TraceConfig::new(Mode::Adaptive, Budget::NMax(50_000));
    t.seed = 2;
    let out = Tracer::new(PreparedScene::new(scene.clone(), &rt).unwrap())
        .trace(&t)
        .unwrap();
    let maps = Maps::build(&out.records());
    let mut cfg = RenderConfig::new(24, 24);
    cfg.spp = 16;
    cfg.view = View::Full;
    let cached = render(&scene, &rt, Some(&maps), &cfg, &|_, _| {}).unwrap();
    cfg.cache_stride = 0;
    let knn = render(&scene, &rt, Some(&maps), &cfg, &|_, _| {}).unwrap();
    assert!(cached.pixels.iter().all(|p| p.is_finite()));
    let (a, b) = (cached.mean(), knn.mean());
    let rel = ((a - b).abs() / b).max_element();
    assert!(rel < 0.02, "{a} vs {b}");
}

/// Maps built full-only (what the default render reads) are refused, with a
/// clear error, by settings that read the primary or indirect map; the
/// default settings render from them the same image as from all three maps.
#[test]
fn full_only_maps_serve_the_default_render_and_refuse_the_others() {
    let scene = Scene::cornell().unwrap();
    let device = Device::new().unwrap();
    let rt = scene.embree_geometry(&device).unwrap();
    let cfg = TraceConfig::new(Mode::Adaptive, Budget::NMax(20_000));
    let tracer = Tracer::new(PreparedScene::new(scene.clone(), &rt).unwrap());
    let out = tracer.trace(&cfg).unwrap();
    let all = Maps::from_photons(out.photons.clone(), out.frame);
    let full = Maps::full_only(out.photons, out.frame);
    assert!(full.is_full_only() && !all.is_full_only());
    let mut rc = RenderConfig::new(12, 12);
    rc.spp = 2;
    assert!(!rc.reads_split_maps());
    let a = render(&scene, &rt, Some(&all), &rc, &|_, _| {}).unwrap();
    let b = render(&scene, &rt, Some(&full), &rc, &|_, _| {}).unwrap();
    assert_eq!(a.pixels, b.pixels);
    for view in [View::Map { primary_only: true }, View::Full] {
        let mut c = rc.clone();
        c.view = view;
        c.final_gather = 0;
        assert!(c.reads_split_maps());
        match render(&scene, &rt, Some(&full), &c, &|_, _| {}) {
            Err(Error::InvalidParameter { name, reason }) => {
                assert!(
                    name.contains("photon map") && reason.contains("full-only"),
                    "{reason}"
                );
            }
            other => panic!("{view:?}: {:?}", other.map(|_| ())),
        }
    }
}
