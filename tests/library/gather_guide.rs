//! The final gather's directions drawn from the irradiance cache's guide
//! (`GatherDirections::Guided`, the default) against the BRDF's: the same
//! image in expectation. (That it lowers the gather's variance is checked
//! point by point on `door`, in `render::gather_guide_tests`.)

use crate::common::{assert_sigmas, seed, MeanVar};
use crate::fixtures::{grey, rendered, traced};
use adaptive_pm::render::{GatherDirections, RenderConfig};

/// A 48² render of 8 samples a pixel, the emitters hidden.
fn config(directions: GatherDirections, seed: u64) -> RenderConfig {
    let mut cfg = RenderConfig::new(48, 48);
    cfg.spp = 8;
    cfg.gather_directions = directions;
    cfg.show_emitters = false;
    cfg.seed = seed;
    cfg
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
    let brdf = grey(&rendered(&tracer, &maps, &config(GatherDirections::Brdf, s)).0);
    let guided = grey(
        &rendered(
            &tracer,
            &maps,
            &config(GatherDirections::Guided, s ^ 0x9e37),
        )
        .0,
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
