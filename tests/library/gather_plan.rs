//! Gather rays spread by a pilot's variance (`GatherAllocation::Variance`,
//! the default): the image's expectation is the uniform gather's, the mean
//! count is the one asked for, the noise is lower where the gather's noise
//! is uneven, and the counts do not depend on threads or tiles.

use crate::common::{assert_sigmas, seed, MeanVar};
use crate::fixtures::{grey, rendered, traced};
use adaptive_pm::render::{GatherAllocation, Image, RenderConfig};

fn config(side: u32, spp: u32, allocation: GatherAllocation, seed: u64) -> RenderConfig {
    let mut cfg = RenderConfig::new(side, side);
    cfg.spp = spp;
    cfg.gather_allocation = allocation;
    cfg.show_emitters = false;
    cfg.seed = seed;
    cfg
}

/// The image's mean with the counts spread by variance equals the uniform
/// gather's, on one map (so the map's own error is the same in both): the
/// mean of the per-pixel differences of two independent renders, against
/// its standard error over the pixels (each pixel its own streams, the
/// pilot's apart from both), at 4 sigma. A gather that divided by the
/// mean count instead of the pixel's own would read several sigma off.
#[test]
fn spreading_the_gather_keeps_the_images_expectation() {
    let (tracer, maps) = traced("cornell", 20_000);
    let s = seed(3);
    let uniform = rendered(&tracer, &maps, &config(48, 8, GatherAllocation::Uniform, s)).0;
    let spread = rendered(
        &tracer,
        &maps,
        &config(48, 8, GatherAllocation::Variance, s ^ 0x5eed),
    )
    .0;
    let d = MeanVar::of(grey(&spread).iter().zip(grey(&uniform)).map(|(a, b)| a - b));
    let mean = MeanVar::of(grey(&uniform)).mean();
    let se = (d.variance() / d.count() as f64).sqrt();
    eprintln!(
        "variance - uniform: {:+.5} +- {:.5} of the mean {mean:.5}",
        d.mean(),
        se
    );
    assert_sigmas("spread gather vs uniform", d.mean(), se, 4.0);
}

/// The counts' mean over the image is the mean asked for, and the spread
/// gather is less noisy than the uniform one on the Cornell box, whose
/// ceiling and upper walls (their gather rays find the lit floor or the
/// dark walls) are several times noisier than its floor. Each
/// allocation's noise is the per-pixel squared difference of two renders
/// of other seeds; their ratio's standard error comes from 8 x 8 pixel
/// blocks (wider than the pilot's pooling square, so blocks are nearly
/// independent), delta method; the ratio must be below 1 by 4 sigma. Over
/// 14 sweep seeds it read 0.67 to 0.75, each +- 0.035 to 0.041 (on `door`,
/// 0.54 to 0.73 but +- 0.08 to 0.14: its fireflies make the noise of the
/// noise too large for a 4-sigma test of this size).
#[test]
fn spreading_the_gather_lowers_the_noise_where_it_is_uneven() {
    const SIDE: u32 = 96;
    const BLOCK: usize = 8;
    let (tracer, maps) = traced("cornell", 100_000);
    let squares = |allocation| {
        let a = rendered(&tracer, &maps, &config(SIDE, 8, allocation, seed(11)));
        let b = rendered(&tracer, &maps, &config(SIDE, 8, allocation, seed(12)));
        let sq: Vec<f64> = grey(&a.0)
            .iter()
            .zip(grey(&b.0))
            .map(|(x, y)| (x - y) * (x - y))
            .collect();
        (block_sums(&sq, SIDE as usize, BLOCK), a.1.mean_gather)
    };
    let (uniform, g_uniform) = squares(GatherAllocation::Uniform);
    let (spread, g_spread) = squares(GatherAllocation::Variance);
    assert_eq!(g_uniform, 2.0);
    assert!((g_spread - 2.0).abs() < 0.05, "mean gather {g_spread}");
    let (su, ss): (f64, f64) = (uniform.iter().sum(), spread.iter().sum());
    let ratio = ss / su;
    let residuals = MeanVar::of(spread.iter().zip(&uniform).map(|(s, u)| s - ratio * u));
    let n = residuals.count() as f64;
    let se = residuals.variance().sqrt() * n.sqrt() / su;
    eprintln!("spread / uniform variance: {ratio:.3} +- {se:.3}; mean gather {g_spread}");
    assert!(
        ratio + 4.0 * se < 1.0,
        "spread / uniform variance {ratio:.3} +- {se:.3}"
    );
}

/// Sums of `values` (a `side x side` image's pixels) over blocks of
/// `block x block` pixels.
fn block_sums(values: &[f64], side: usize, block: usize) -> Vec<f64> {
    let per_row = side.div_ceil(block);
    let mut sums = vec![0.0; per_row * per_row];
    for (i, v) in values.iter().enumerate() {
        let (x, y) = (i % side, i / side);
        sums[(y / block) * per_row + x / block] += v;
    }
    sums
}

/// The pilot covers the whole image with a stream per pixel: a render on
/// one thread and on two, and a tile of rows, give the whole image's
/// pixels to the bit.
#[test]
fn the_plan_is_the_same_on_any_thread_count_and_tile() {
    let (tracer, maps) = traced("cornell", 20_000);
    let cfg = config(24, 4, GatherAllocation::Variance, 5);
    let on = |threads: usize, cfg: &RenderConfig| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| rendered(&tracer, &maps, cfg).0)
    };
    let bits = |img: &Image| -> Vec<[u32; 3]> {
        img.pixels
            .iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect()
    };
    let whole = on(1, &cfg);
    assert_eq!(bits(&whole), bits(&on(2, &cfg)));
    let mut tile = cfg.clone();
    tile.rows = Some((8, 16));
    let rows = on(2, &tile);
    assert_eq!(bits(&rows), bits(&whole)[8 * 24..16 * 24].to_vec());
}
