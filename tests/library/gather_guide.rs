//! The final gather's directions drawn from the irradiance cache's guide
//! (`GatherDirections::Guided`, the default) against the BRDF's: the same
//! image in expectation. (That it lowers the gather's variance is checked
//! point by point on `door`, in `render::gather_guide_tests`.)

use crate::common::{assert_sigmas, seed, MeanVar};
use adaptive_pm::embree::{CommittedScene, Device};
use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
use adaptive_pm::render::{render_with, GatherDirections, Image, RenderConfig, RenderMaps};
use adaptive_pm::scene::Scene;

fn traced(scene: &str, n_max: u64) -> (Tracer<CommittedScene>, RenderMaps) {
    let scene = Scene::open(scene).unwrap();
    let tracer = Tracer::new(scene.commit(&Device::new().unwrap()).unwrap());
    let mut t = TraceConfig::new(Mode::Adaptive, Budget::NMax(n_max));
    t.seed = 7;
    let out = tracer.trace(&t).unwrap();
    let maps = RenderConfig::new(8, 8).build_maps(out.photons, out.frame);
    (tracer, maps)
}

/// Per pixel, the mean over its channels, of one render.
fn grey(
    tracer: &Tracer<CommittedScene>,
    maps: &RenderMaps,
    (side, spp): (u32, u32),
    directions: GatherDirections,
    seed: u64,
) -> Vec<f64> {
    let mut cfg = RenderConfig::new(side, side);
    cfg.spp = spp;
    cfg.gather_directions = directions;
    cfg.show_emitters = false;
    cfg.seed = seed;
    let img: Image = render_with(tracer.prepared(), Some(maps), None, &cfg, &|_, _| {})
        .unwrap()
        .0;
    img.pixels
        .iter()
        .map(|p| p.as_dvec3().element_sum() / 3.0)
        .collect()
}

/// On one map (so the map's own error is common to both), the mean of the
/// per-pixel differences between a guided render and an independent
/// BRDF-sampled one is 0 within 4 sigma of its standard error over the
/// pixels. A guide whose weight divided by another density than the one
/// its directions were drawn from would read several sigma off.
#[test]
fn guided_gathers_keep_the_images_expectation() {
    let (tracer, maps) = traced("cornell", 20_000);
    let s = seed(5);
    let brdf = grey(&tracer, &maps, (48, 8), GatherDirections::Brdf, s);
    let guided = grey(
        &tracer,
        &maps,
        (48, 8),
        GatherDirections::Guided,
        s ^ 0x9e37,
    );
    let d = MeanVar::of(guided.iter().zip(&brdf).map(|(a, b)| a - b));
    let se = (d.variance() / d.count() as f64).sqrt();
    eprintln!(
        "guided - brdf: {:+.5} +- {:.5} of the mean {:.5}",
        d.mean(),
        se,
        MeanVar::of(brdf.iter().copied()).mean()
    );
    assert_sigmas("guided gather vs brdf", d.mean(), se, 4.0);
}
