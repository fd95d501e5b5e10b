//! `render --spp auto` (`render::render_progressive`): the noise it
//! estimates from two halves against the difference of two independent
//! renders, the emitters added after, and determinism.

use crate::common::{assert_sigmas, seed, MeanVar};
use adaptive_pm::embree::Device;
use adaptive_pm::embree::EmbreeScene;
use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
use adaptive_pm::render::{
    light_pixels, render_progressive, NoiseTarget, Progressive, RenderConfig, RenderMaps,
};
use adaptive_pm::scene::Scene;

fn cornell() -> (Tracer<adaptive_pm::embree::CommittedScene>, RenderMaps) {
    let tracer = Tracer::new(
        Scene::cornell()
            .unwrap()
            .commit(&Device::new().unwrap())
            .unwrap(),
    );
    let mut t = TraceConfig::new(Mode::Adaptive, Budget::NMax(20_000));
    t.seed = 7;
    let out = tracer.trace(&t).unwrap();
    let maps = RenderConfig::new(8, 8).build_maps(out.photons, out.frame);
    (tracer, maps)
}

fn progressive(
    prepared: &EmbreeScene,
    maps: &RenderMaps,
    cfg: &RenderConfig,
    target: NoiseTarget,
) -> Progressive {
    let cfg = cfg.check().unwrap();
    render_progressive(prepared, Some(maps), &cfg, &target, &|_, _| {}, &mut |_| {})
        .unwrap()
        .0
}

/// Two renders of other seeds differ by `sqrt(n1^2 + n2^2)` times the
/// image mean, `n` each one's estimated noise: the estimate is the noise
/// the image really has.
#[test]
fn the_estimated_noise_is_the_noise_between_independent_renders() {
    let (tracer, maps) = cornell();
    let prepared = tracer.prepared();
    let mut cfg = RenderConfig::new(48, 48);
    cfg.show_emitters = false;
    let keep: Vec<bool> = light_pixels(prepared, &cfg)
        .unwrap()
        .iter()
        .map(|l| !l)
        .collect();
    // A target no render reaches: both stop at max_spp, the same spp.
    let target = NoiseTarget {
        noise: 1e-4,
        max_spp: 16,
    };
    cfg.seed = seed(0x9A11);
    let p = progressive(prepared, &maps, &cfg, target);
    cfg.seed = seed(0x9A12);
    let q = progressive(prepared, &maps, &cfg, target);
    assert_eq!((p.spp, q.spp), (16, 16));
    assert!(!p.converged && !q.converged);
    let (mut d2, mut sum, mut n) = (MeanVar::default(), 0.0, 0usize);
    for ((a, b), &k) in p.image.pixels.iter().zip(&q.image.pixels).zip(&keep) {
        if k {
            d2.push((*a - *b).as_dvec3().length_squared() / 3.0);
            sum += (*a + *b).as_dvec3().element_sum() / 6.0;
            n += 1;
        }
    }
    let mean = sum / n as f64;
    let predicted = (p.noise.powi(2) + q.noise.powi(2)) * mean * mean;
    let ratio = d2.mean() / predicted;
    // The estimates come from as many pixels as the difference: their
    // relative noise is about the difference's, hence sqrt 2.
    let sigma = std::f64::consts::SQRT_2 * d2.std_error() / d2.mean();
    assert_sigmas("mse between renders / predicted", ratio - 1.0, sigma, 4.0);
}

/// With the emitters shown, the image is the hidden-emitter image plus the
/// emission the camera sees: exactly 0 off the light, the light's constant
/// radiance inside it.
#[test]
fn shown_emitters_are_added_after_the_noise_is_measured() {
    let (tracer, maps) = cornell();
    let prepared = tracer.prepared();
    let (w, h) = (80u32, 80u32);
    let mut cfg = RenderConfig::new(w, h);
    let target = NoiseTarget {
        noise: 0.2,
        max_spp: 64,
    };
    let shown = progressive(prepared, &maps, &cfg, target);
    cfg.show_emitters = false;
    let hidden = progressive(prepared, &maps, &cfg, target);
    // The halves render with the emitters hidden in both: same rounds.
    assert_eq!(shown.spp, hidden.spp);
    assert_eq!(shown.noise, hidden.noise);
    let light = light_pixels(prepared, &cfg).unwrap();
    let at = |x: u32, y: u32| light[(y * w + x) as usize];
    let mut inside = Vec::new();
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let i = (y * w + x) as usize;
            let d = shown.image.pixels[i] - hidden.image.pixels[i];
            let near = (0..9).any(|j| at(x + j % 3 - 1, y + j / 3 - 1));
            if !near {
                assert_eq!(d, glam::Vec3::ZERO, "pixel ({x}, {y}) is off the light");
            } else if (0..9).all(|j| at(x + j % 3 - 1, y + j / 3 - 1)) {
                inside.push(d);
            }
        }
    }
    assert!(!inside.is_empty(), "the camera sees the light");
    let l0 = inside[0];
    assert!(l0.min_element() > 0.0);
    for d in &inside {
        assert!(
            (*d - l0).abs().max_element() <= 1e-5 * l0.max_element(),
            "{d} vs {l0}"
        );
    }
}

#[test]
fn the_same_settings_give_the_same_image_on_any_thread_count() {
    let (tracer, maps) = cornell();
    let prepared = tracer.prepared();
    let cfg = RenderConfig::new(24, 24);
    let target = NoiseTarget {
        noise: 0.15,
        max_spp: 256,
    };
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| progressive(prepared, &maps, &cfg, target))
    };
    let (a, b) = (run(1), run(2));
    assert!(a.converged, "noise {} after {} spp", a.noise, a.spp);
    assert!(a.noise <= 0.15);
    assert_eq!((a.spp, a.noise.to_bits()), (b.spp, b.noise.to_bits()));
    assert!(a
        .image
        .pixels
        .iter()
        .zip(&b.image.pixels)
        .all(|(p, q)| p.to_array().map(f32::to_bits) == q.to_array().map(f32::to_bits)));
}

#[test]
fn bad_targets_are_refused_before_any_work() {
    let (tracer, maps) = cornell();
    let cfg = RenderConfig::new(8, 8).check().unwrap();
    for (noise, max_spp) in [(0.0, 64), (-1.0, 64), (f64::INFINITY, 64), (0.1, 2)] {
        let t = NoiseTarget { noise, max_spp };
        let r = render_progressive(
            tracer.prepared(),
            Some(&maps),
            &cfg,
            &t,
            &|_, _| {},
            &mut |_| {},
        );
        assert!(
            matches!(r, Err(adaptive_pm::Error::InvalidParameter { .. })),
            "{noise} {max_spp}"
        );
    }
}
