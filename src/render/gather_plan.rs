//! Final-gather rays per pixel where the gather's variance is (`render
//! --gather-allocation variance`): a pilot measures each pixel's gather
//! variance, and the render's gather rays per camera sample go where it is
//! high, their mean per pixel kept at [`RenderConfig::final_gather`](super::RenderConfig::final_gather).
//!
//! - **Why.** On the Cornell box the gather's noise is most of the image's
//!   (one gather ray per sample instead of two doubles the error's square,
//!   a second light sample changes it by 1 %), and it is far from even: a
//!   ceiling pixel, whose gather rays find the lit floor or the dark walls,
//!   has about ten times the variance of a floor pixel.
//! - **Allocation.** With independent rays a pixel's gather adds
//!   `B_i / (spp g_i)` to its variance, `B_i` one gather ray's variance
//!   there, `g_i` its rays per sample, and for a fixed total of rays the
//!   image's sum is least with `g_i ∝ B_i^(1/2)` (the Lagrange condition).
//!   But the render's gather directions are stratified over the pixel's
//!   samples, and a stratified estimate's variance falls faster than `1/g`
//!   where the integrand is smooth (a wall's half of the hemisphere, the
//!   floor seen from the ceiling), which the pilot's independent rays
//!   cannot see: where it falls as `1/g^2` the optimum is `g_i ∝
//!   B_i^(1/3)`, and that is the rule ([`SIGMA_POWER`]; it also measured
//!   lower noise than the square root on the Cornell box and on `door`,
//!   docs/rendering.md). The counts are clamped to
//!   `1..=MOST_PER_MEAN` times the mean (a pixel always gathers, and a
//!   misjudged one cannot take the image's rays), the scale set so that
//!   their mean is the mean asked for, and each pixel's real count is
//!   rounded up or down by a hash of the pixel (its expectation kept).
//! - **Pilot.** [`PILOT_GATHER`] gather rays from one camera sample per
//!   pixel, each ray's luminance contribution; their spread about their own
//!   mean (the same point, so the pixel's edges and direct light are not in
//!   it) is pooled over a square of `2 POOL_RADIUS + 1` pixels. Its own
//!   random streams: the render's samples do not depend on it, only their
//!   count does.
//! - **Unbiased.** Every sample's gather, with any number of rays at least
//!   1, is an unbiased estimate; the counts depend only on the pilot, drawn
//!   apart from the samples they weigh. The image's expectation is the
//!   uniform gather's.
//! - **Deterministic.** The pilot covers the whole image, a tile's render
//!   included, with one stream per pixel, and the plan is summed in one
//!   order: the same counts whatever the threads or the tiling.

use super::camera::CameraRays;
use super::film::{self, Sample};
use super::integrator::{Ctx, SampleScratch};
use super::{CheckedRender, RenderMaps, MAX_GATHER};
use crate::rng::{hash2, Rng};
use crate::sampling::luminance;
use glam::Vec3;
use rayon::prelude::*;

/// How the final gather's rays are spread over the pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GatherAllocation {
    /// [`RenderConfig::final_gather`](super::RenderConfig::final_gather)
    /// rays per camera sample in every pixel.
    Uniform,
    /// That many on average, more where a pilot measured more gather
    /// variance (this module).
    #[default]
    Variance,
}

impl GatherAllocation {
    /// The name the command line takes.
    pub fn name(self) -> &'static str {
        match self {
            GatherAllocation::Uniform => "uniform",
            GatherAllocation::Variance => "variance",
        }
    }
}

/// Where the final gather's directions come from at a diffuse surface.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GatherDirections {
    /// The BRDF's sampling (the cosine).
    Brdf,
    /// The irradiance cache's guide: a histogram of the directions the
    /// indirect photons came from there, mixed half and half with the
    /// cosine ([`Guide`](super::cache::Guide)). Elsewhere, the BRDF's.
    #[default]
    Guided,
}

impl GatherDirections {
    /// The name the command line takes.
    pub fn name(self) -> &'static str {
        match self {
            GatherDirections::Brdf => "brdf",
            GatherDirections::Guided => "guided",
        }
    }
}

impl std::str::FromStr for GatherDirections {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        match s {
            "brdf" => Ok(GatherDirections::Brdf),
            "guided" => Ok(GatherDirections::Guided),
            _ => Err(crate::Error::param(
                "gather directions",
                format!("expected guided or brdf, got `{s}`"),
            )),
        }
    }
}

impl std::str::FromStr for GatherAllocation {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        match s {
            "uniform" => Ok(GatherAllocation::Uniform),
            "variance" => Ok(GatherAllocation::Variance),
            _ => Err(crate::Error::param(
                "gather allocation",
                format!("expected uniform or variance, got `{s}`"),
            )),
        }
    }
}

/// Gather rays per pilot camera sample: 3 degrees of freedom a pixel.
pub const PILOT_GATHER: u32 = 4;
/// The pooling square's half side, in pixels (7 x 7 pixels, about 150
/// degrees of freedom per pixel's variance).
pub const POOL_RADIUS: usize = 3;
/// The counts follow the pooled standard deviation to this power: `B^(1/3)`
/// of the variance `B` (see the module docs).
pub const SIGMA_POWER: f64 = 2.0 / 3.0;
/// A pixel's most gather rays per sample, over their mean.
pub const MOST_PER_MEAN: f64 = 4.0;
/// Salt of the pilot's streams.
const PILOT_SALT: u64 = 0x9117_00a7;

/// Gather rays per camera sample, per pixel of the whole image.
#[derive(Clone, Debug, PartialEq)]
pub struct GatherPlan {
    width: usize,
    counts: Vec<u16>,
    /// Seconds the pilot and the plan took.
    pub seconds: f64,
}

impl GatherPlan {
    /// Gather rays per camera sample of pixel `(x, y)` of the whole image.
    pub(super) fn count(&self, x: u32, y: u32) -> u32 {
        u32::from(self.counts[y as usize * self.width + x as usize])
    }

    /// The mean count over the image.
    pub fn mean(&self) -> f64 {
        let sum: u64 = self.counts.iter().map(|&c| u64::from(c)).sum();
        sum as f64 / self.counts.len().max(1) as f64
    }
}

/// One pixel's pilot: the sum of squared deviations of its gather rays'
/// contributions about their mean, and its degrees of freedom (0 when the
/// camera sample found no surface).
#[derive(Clone, Copy, Default)]
struct Spread {
    squares: f32,
    dof: f32,
}

/// Bytes a plan holds per pixel while it is made: two [`Spread`]s, the
/// pooled deviation and the count.
const BYTES_PER_PIXEL: u64 = 8 + 8 + 4 + 2;

/// The plan for `cfg` (its whole image, whatever its rows). `None` unless
/// it gathers with [`GatherAllocation::Variance`] and more than one ray
/// on average, or when the plan would not fit in a quarter of the
/// available memory: the render then gathers uniformly.
pub(super) fn plan(
    ctx: &Ctx<'_>,
    maps: &RenderMaps,
    rays: &CameraRays,
    cfg: &CheckedRender,
) -> Option<GatherPlan> {
    // A mean of one ray leaves nothing to move: every pixel gathers with
    // at least one.
    if cfg.gather_allocation != GatherAllocation::Variance
        || !ctx.batches()
        || cfg.final_gather <= 1
    {
        return None;
    }
    let start = std::time::Instant::now();
    let (w, h) = (cfg.width as usize, cfg.height as usize);
    // An image near the memory's limit renders with the uniform gather
    // rather than fail for its plan (the stats show no plan).
    if (w * h) as u64 * BYTES_PER_PIXEL > crate::engine::config::available_memory() / 4 {
        return None;
    }
    let seed = hash2(cfg.seed, PILOT_SALT);
    let mut spreads = vec![Spread::default(); w * h];
    // A row a task, as the render's (`film::develop`): rayon's default
    // runs of rows left one thread idle at the end.
    spreads
        .par_chunks_mut(w)
        .with_max_len(1)
        .enumerate()
        .for_each(|(y, row)| {
            let mut sc = SampleScratch::new(cfg.k);
            for (x, spread) in row.iter_mut().enumerate() {
                let mut rng = Rng::new(hash2(seed, (y * w + x) as u64));
                let sample = Sample {
                    x: x as u32,
                    y: y as u32,
                    s: 0,
                };
                let ray = film::camera_ray(rays, sample, rng.next_2d());
                *spread = pilot_pixel(ctx, maps, ray, &mut rng, &mut sc);
            }
        });
    let weights: Vec<f32> = pooled_sigma(&spreads, w, h)
        .into_iter()
        .map(|sigma| f64::from(sigma).powf(SIGMA_POWER) as f32)
        .collect();
    let counts = allocate(&weights, cfg.final_gather, seed);
    Some(GatherPlan {
        width: w,
        counts,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// The spread of [`PILOT_GATHER`] gather rays' contributions at the
/// surface `ray` finds.
fn pilot_pixel(
    ctx: &Ctx<'_>,
    maps: &RenderMaps,
    ray: crate::raycast::Ray,
    rng: &mut Rng,
    sc: &mut SampleScratch,
) -> Spread {
    let mut seen = Vec3::ZERO;
    let Some(s) = ctx.trace(ray, u32::MAX, rng, &mut seen) else {
        return Spread::default();
    };
    let mut c = [0.0f64; PILOT_GATHER as usize];
    let guide = ctx.guide_at(&s);
    for cj in &mut c {
        let u = rng.next_2d();
        if let Some((weight, ray)) = ctx.gather_ray_with(&s, u, guide.as_ref()) {
            let mut emitted = Vec3::ZERO;
            if let Some(y) = ctx.trace(ray, u32::MAX, rng, &mut emitted) {
                let l = weight * y.throughput * ctx.cached_radiance(maps, &y, rng, sc);
                *cj = f64::from(luminance(s.throughput * l));
            }
        }
    }
    let mean = c.iter().sum::<f64>() / c.len() as f64;
    let squares = c.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() as f32;
    if !squares.is_finite() {
        return Spread::default();
    }
    Spread {
        squares,
        dof: (PILOT_GATHER - 1) as f32,
    }
}

/// Each pixel's gather standard deviation, pooled over the square of
/// [`POOL_RADIUS`] around it (0 where no pixel of it found a surface).
fn pooled_sigma(spreads: &[Spread], w: usize, h: usize) -> Vec<f32> {
    // A box sum along rows, then along columns (sums in f64).
    let box_sum = |get: &dyn Fn(usize) -> Spread, n: usize, out: &mut dyn FnMut(usize, Spread)| {
        for i in 0..n {
            let lo = i.saturating_sub(POOL_RADIUS);
            let hi = (i + POOL_RADIUS).min(n - 1);
            let (mut squares, mut dof) = (0.0f64, 0.0f64);
            for j in lo..=hi {
                let v = get(j);
                squares += f64::from(v.squares);
                dof += f64::from(v.dof);
            }
            out(
                i,
                Spread {
                    squares: squares as f32,
                    dof: dof as f32,
                },
            );
        }
    };
    let mut rows = vec![Spread::default(); w * h];
    for y in 0..h {
        box_sum(&|x| spreads[y * w + x], w, &mut |x, s| rows[y * w + x] = s);
    }
    let mut sigma = vec![0.0f32; w * h];
    for x in 0..w {
        box_sum(&|y| rows[y * w + x], h, &mut |y, s| {
            sigma[y * w + x] = if s.dof > 0.0 {
                (s.squares / s.dof).sqrt()
            } else {
                0.0
            };
        });
    }
    sigma
}

/// Counts proportional to `sigma`, clamped to `1..=MOST_PER_MEAN mean`,
/// scaled so that their mean is `mean`, rounded by a hash of each pixel.
/// All `mean` where the pilot saw no variance.
fn allocate(sigma: &[f32], mean: u32, seed: u64) -> Vec<u16> {
    let target = f64::from(mean);
    let most = (MOST_PER_MEAN * target).min(f64::from(MAX_GATHER));
    let clamped = |scale: f64, s: f32| (scale * f64::from(s)).clamp(1.0, most);
    let total = |scale: f64| sigma.iter().map(|&s| clamped(scale, s)).sum::<f64>();
    let sum: f64 = sigma.iter().map(|&s| f64::from(s)).sum();
    if sum.is_nan() || sum <= 0.0 || target <= 1.0 {
        return vec![mean as u16; sigma.len()];
    }
    // The mean of the clamped counts grows with the scale: bisect for it.
    let wanted = target * sigma.len() as f64;
    // At `hi` every pixel with variance takes the most: the largest total.
    let least = sigma
        .iter()
        .map(|&s| f64::from(s))
        .filter(|&s| s > 0.0)
        .fold(f64::INFINITY, f64::min);
    let (mut lo, mut hi) = (0.0, most / least);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if total(mid) < wanted {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    sigma
        .iter()
        .enumerate()
        .map(|(i, &s)| {
            let u = (hash2(seed, i as u64) >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
            (clamped(hi, s) + u).floor().min(most) as u16
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_follow_sigma_with_the_mean_asked_for() {
        let sigma: Vec<f32> = (0..10_000).map(|i| (i % 100) as f32 / 10.0).collect();
        let counts = allocate(&sigma, 4, 7);
        let mean = counts.iter().map(|&c| f64::from(c)).sum::<f64>() / counts.len() as f64;
        assert!((mean - 4.0).abs() < 0.05, "mean {mean}");
        assert!(counts.iter().all(|&c| (1..=16).contains(&c)));
        // Zero variance gets the least.
        assert_eq!(counts[0], 1);
        // In between, proportional: sigma 2.0 against 4.0.
        let at = |k: usize| {
            (0..100)
                .map(|r| f64::from(counts[r * 100 + k]))
                .sum::<f64>()
                / 100.0
        };
        let ratio = at(40) / at(20);
        assert!((ratio - 2.0).abs() < 0.15, "ratio {ratio}");
    }

    #[test]
    fn a_pixel_takes_at_most_four_times_the_mean() {
        let mut sigma = vec![1.0f32; 1000];
        sigma[0] = 1e6;
        let counts = allocate(&sigma, 2, 3);
        assert_eq!(counts[0], 8);
        assert!(counts[1..].iter().all(|&c| c == 2 || c == 1));
    }

    #[test]
    fn no_variance_gives_the_uniform_count() {
        assert!(allocate(&[0.0; 64], 3, 1).iter().all(|&c| c == 3));
        assert!(allocate(&[1.0, 5.0], 1, 1).iter().all(|&c| c == 1));
    }

    #[test]
    fn pooling_is_over_the_square_and_skips_empty_pixels() {
        let (w, h) = (9, 9);
        let mut spreads = vec![Spread::default(); w * h];
        spreads[4 * w + 4] = Spread {
            squares: 12.0,
            dof: 3.0,
        };
        let sigma = pooled_sigma(&spreads, w, h);
        // Within the square of the one pixel with a surface: its sigma.
        assert_eq!(sigma[4 * w + 4], 2.0);
        assert_eq!(sigma[(4 + POOL_RADIUS) * w + 4 - POOL_RADIUS], 2.0);
        // Outside: nothing measured.
        assert_eq!(sigma[0], 0.0);
    }
}
