//! The renderer as an oracle: the photon map's direct irradiance against a
//! quadrature over the light, convergence of every mode, EXR round trip, and
//! bad input. Tiny images, small budgets, fixed seeds.

use adaptive_pm::embree::{CommittedScene, Device};
use adaptive_pm::emitter::CosN;
use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
use adaptive_pm::render::{
    floor_points, irradiance_estimate, quadrature_irradiance, render, rmse, Image, Lookup,
    RenderConfig, RenderMaps, View,
};
use adaptive_pm::scene::{PreparedScene, Scene};
use adaptive_pm::Error;
use glam::Vec3;

fn cornell(n: f32) -> Scene {
    let mut s = Scene::cornell().unwrap();
    s.set_cosn(CosN::new(n).unwrap());
    s
}

fn maps(scene: &Scene, rt: &CommittedScene, mode: Mode, n_max: u64, seed: u64) -> RenderMaps {
    let mut cfg = TraceConfig::new(mode, Budget::NMax(n_max));
    cfg.seed = seed;
    let out = Tracer::new(PreparedScene::new(scene.clone(), &rt).unwrap())
        .trace(&cfg)
        .unwrap();
    RenderMaps::build(&out.records())
}

/// The quadrature irradiance averaged over a disc of radius `r` about `x`
/// (in the floor plane) with the cone filter's weights `1 - d / r`: what the
/// photon estimate converges to for that radius, so the comparison has no
/// kernel bias left, only photon noise. Also says whether every node of the
/// disc sees the whole light (no shadow in the kernel).
fn cone_smoothed(scene: &Scene, rt: &CommittedScene, x: Vec3, r: f32) -> (f64, bool) {
    let m = 9;
    let (mut sum, mut wsum, mut lit) = (0.0f64, 0.0f64, true);
    for i in 0..m {
        for j in 0..m {
            let dx = (2.0 * (i as f32 + 0.5) / m as f32 - 1.0) * r;
            let dz = (2.0 * (j as f32 + 0.5) / m as f32 - 1.0) * r;
            let d = (dx * dx + dz * dz).sqrt();
            if d >= r {
                continue;
            }
            let p = x + Vec3::new(dx, 0.0, dz);
            let shadowed = quadrature_irradiance(scene, Some(rt), p, Vec3::Y, 12);
            let open = quadrature_irradiance(scene, None, p, Vec3::Y, 12);
            lit &= (shadowed - open).abs().max_element() <= 1e-6 * open.max_element();
            let w = (1.0 - d / r) as f64;
            sum += w * open.x as f64;
            wsum += w;
        }
    }
    (sum / wsum, lit)
}

/// Depth-0 photons on the floor against the quadrature of the light, for a
/// diffuse light (n = 0) and a sharp one (n = 50).
///
/// Tolerance: the cone-filtered estimate over a Poisson process of photons
/// has relative variance `int w^2 / (int w)^2 / (lambda) = 1.5 / k` (the
/// filter's `pi r^2 / 6` over `(pi r^2 / 3)^2`), so sd = 1.22 / sqrt(k). Each
/// point must lie within 4.5 sd; the mean ratio over M far-apart points within
/// 4 sd / sqrt(M). The kernel bias is removed by comparing with the
/// quadrature smoothed by the same kernel at the estimate's own radius;
/// points whose kernel sees a shadow are skipped.
#[test]
fn primary_map_irradiance_matches_the_light_quadrature() {
    let device = Device::new().unwrap();
    for n in [0.0f32, 50.0] {
        let scene = cornell(n);
        let rt = scene.embree_geometry(&device).unwrap();
        // Classic mode: every depth-0 photon of the light has the same power.
        let m = maps(&scene, &rt, Mode::Classic, 300_000, 11);
        let k = 400;
        let sd = 1.22 / (k as f64).sqrt();
        // A grid over the floor, 5 % in from its edges.
        let candidates: Vec<Vec3> = floor_points(&scene, "floor", 12, 12, 0.05)
            .into_iter()
            .map(|p| p.position)
            .collect();
        let mut ratios = Vec::new();
        let mut scratch = Vec::new();
        for x in candidates {
            let lk = Lookup {
                k,
                max_radius: f32::INFINITY,
            };
            let est = irradiance_estimate(&m.primary, x, Vec3::Y, lk, &mut scratch);
            let (expect, lit) = cone_smoothed(&scene, &rt, x, est.radius);
            // Skip shadows and the dim tail of the sharp lobe (too few photons there).
            if !lit || expect <= 0.0 || est.found < k {
                continue;
            }
            let ratio = est.value.x as f64 / expect;
            assert!(
                (ratio - 1.0).abs() < 4.5 * sd,
                "n = {n}, x = {x}: estimate {} vs quadrature {expect} (r = {})",
                est.value.x,
                est.radius
            );
            ratios.push(ratio);
        }
        assert!(
            ratios.len() >= 8,
            "n = {n}: only {} usable points",
            ratios.len()
        );
        let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
        let tol = 4.0 * sd / (ratios.len() as f64).sqrt();
        eprintln!(
            "n = {n}: {} points, mean ratio {mean:.4} (tolerance {tol:.4})",
            ratios.len()
        );
        assert!(
            (mean - 1.0).abs() < tol,
            "n = {n}: mean ratio {mean} over {} points (tolerance {tol})",
            ratios.len()
        );
    }
}

/// Error of the map view against a larger-budget reference falls when the
/// budget grows 16x, for every mode. k grows as sqrt(N) (x4) so the noise
/// (1/sqrt(k)) halves and the kernel bias (r^2 ~ k/N) quarters: the error must
/// fall well beyond the reference's own noise (1.22/sqrt(1000) ~ 4 %).
#[test]
fn image_error_falls_as_the_budget_grows_in_every_mode() {
    let device = Device::new().unwrap();
    let scene = Scene::cornell().unwrap();
    let rt = scene.embree_geometry(&device).unwrap();
    let view_cfg = |k: usize| {
        let mut c = RenderConfig::new(20, 20);
        c.view = View::Map {
            primary_only: false,
        };
        c.k = k;
        c
    };
    let reference_maps = maps(&scene, &rt, Mode::Classic, 1_000_000, 99);
    let reference = render(
        &scene,
        &rt,
        Some(&reference_maps),
        &view_cfg(1000),
        &|_, _| {},
    )
    .unwrap();
    for mode in Mode::ALL {
        let errors: Vec<f64> = [(4_000u64, 20usize), (64_000, 80)]
            .iter()
            .map(|&(n, k)| {
                let m = maps(&scene, &rt, mode, n, 5);
                let img = render(&scene, &rt, Some(&m), &view_cfg(k), &|_, _| {}).unwrap();
                rmse(&img, &reference).unwrap()
            })
            .collect();
        assert!(
            errors[1] < 0.8 * errors[0],
            "{}: error {:?} did not fall",
            mode.name(),
            errors
        );
    }
}

/// The full view (direct + indirect map) and the map view estimate the same
/// radiance: their means over the image agree within the noise.
#[test]
fn full_and_map_views_agree_on_the_mean() {
    let device = Device::new().unwrap();
    let scene = Scene::cornell().unwrap();
    let rt = scene.embree_geometry(&device).unwrap();
    let m = maps(&scene, &rt, Mode::Adaptive, 50_000, 3);
    let mut cfg = RenderConfig::new(24, 24);
    cfg.spp = 4;
    let full = render(&scene, &rt, Some(&m), &cfg, &|_, _| {})
        .unwrap()
        .mean();
    cfg.view = View::Map {
        primary_only: false,
    };
    let map = render(&scene, &rt, Some(&m), &cfg, &|_, _| {})
        .unwrap()
        .mean();
    // Image means average hundreds of independent estimates: a few percent.
    assert!(
        ((full - map).abs() / map).max_element() < 0.08,
        "full {full} vs map {map}"
    );
    cfg.view = View::DirectOnly;
    let direct = render(&scene, &rt, None, &cfg, &|_, _| {}).unwrap().mean();
    // Indirect light is a real part of the Cornell box.
    assert!(
        direct.x < 0.9 * full.x && direct.x > 0.3 * full.x,
        "{direct} {full}"
    );
}

#[test]
fn tiny_render_round_trips_through_exr_and_is_deterministic() {
    let device = Device::new().unwrap();
    let scene = Scene::cornell().unwrap();
    let rt = scene.embree_geometry(&device).unwrap();
    let m = maps(&scene, &rt, Mode::Adaptive, 10_000, 1);
    let mut cfg = RenderConfig::new(7, 5);
    cfg.spp = 2;
    let img = render(&scene, &rt, Some(&m), &cfg, &|_, _| {}).unwrap();
    let pool = adaptive_pm::embree::thread_pool(1).unwrap();
    let again = pool.install(|| render(&scene, &rt, Some(&m), &cfg, &|_, _| {}).unwrap());
    assert_eq!(img, again, "one thread and many give the same image");
    assert!(img.pixels.iter().all(|p| p.is_finite()));
    assert!(img.mean().max_element() > 0.0);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tiny.exr");
    img.write_exr(&path).unwrap();
    let back = Image::read_exr(&path).unwrap();
    assert_eq!(back, img);
    img.write_png(dir.path().join("tiny.png"), Default::default())
        .unwrap();
    // Only the two final files remain (no temporary left behind).
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(names.len(), 2);
}

#[test]
fn bad_sizes_and_paths_are_clear_errors_without_partial_files() {
    let device = Device::new().unwrap();
    let scene = Scene::cornell().unwrap();
    let rt = scene.embree_geometry(&device).unwrap();
    for (w, h) in [(0, 4), (4, 0), (20_000, 4), (16_384, 16_384 + 1)] {
        let cfg = RenderConfig::new(w, h);
        let e = render(&scene, &rt, None, &cfg, &|_, _| {}).unwrap_err();
        assert!(matches!(e, Error::InvalidParameter { .. }), "{w}x{h}: {e}");
    }
    // A map view without a map.
    let mut cfg = RenderConfig::new(4, 4);
    cfg.view = View::Full;
    assert!(render(&scene, &rt, None, &cfg, &|_, _| {}).is_err());
    cfg.spp = 0;
    assert!(cfg.validate().is_err());

    let img = Image::new(3, 2).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no/such/folder/out.exr");
    let e = img.write_exr(&missing).unwrap_err();
    assert!(e.to_string().contains("cannot access"), "{e}");
    assert!(format!("{:?}", e).contains("does not exist"), "{e:?}");
    // A folder as the output path.
    assert!(img.write_exr(dir.path()).is_err());
    // An unwritable folder (skipped when running as root, which may write anywhere).
    let ro = dir.path().join("ro");
    std::fs::create_dir(&ro).unwrap();
    let mut perm = std::fs::metadata(&ro).unwrap().permissions();
    perm.set_readonly(true);
    std::fs::set_permissions(&ro, perm).unwrap();
    let target = ro.join("out.exr");
    if std::fs::File::create(ro.join("probe")).is_err() {
        assert!(img.write_exr(&target).is_err());
        assert!(!target.exists());
    }
    assert!(std::fs::read_dir(&ro).unwrap().all(|e| {
        let n = e.unwrap().file_name();
        n == "probe" || !n.to_string_lossy().contains("out.exr")
    }));
    // An existing file that is not an EXR image.
    let junk = dir.path().join("junk.exr");
    std::fs::write(&junk, b"not an image").unwrap();
    assert!(Image::read_exr(&junk).is_err());
}
