//! Rendering until the image's own noise reaches a target (`render --spp
//! auto`, the command line's default).
//!
//! The image is rendered as two independent halves `A` and `B` (other
//! seeds, the same settings), in rounds. After each round the relative noise
//! of their mean, over the pixels that are kept (not a light's own),
//! is `rmse(A, B) / 2 / mean`, the same estimate the path-traced references
//! use ([`super::PathHalves::noise_rel`]); the render stops once it is at
//! most [`NoiseTarget::noise`], or at [`NoiseTarget::max_spp`].
//!
//! Each round after the first asks for the samples that `noise ∝ 1 /
//! sqrt(spp)` predicts, with a tenth more, between a quarter of what the
//! halves hold and as many again (at most doubling, so that one round cannot
//! overshoot by much, and at least a quarter, so that the rounds' fixed costs
//! stay small).
//!
//! What this noise does not see: anything the two halves share. For the
//! photon render that is the photon map and the irradiance cache, built
//! once; their error is a bias as far as the image is concerned, and only a
//! reference (or a second map) measures it.
//!
//! Deterministic: each round's halves draw from seeds of `(seed, round)`,
//! the stopping rule reads only the images, so the same settings give the
//! same spp and the same image whatever the thread count.

use super::image::Image;
use super::metrics::relative_rmse_masked;
use super::{CheckedRender, MAX_SPP};
use crate::error::{Error, Result};
use crate::rng::hash2;

/// The default noise target of `--spp auto`: 2 % rms of the mean.
pub const DEFAULT_NOISE_TARGET: f64 = 0.02;

/// The default most samples per pixel of `--spp auto`.
pub const DEFAULT_MAX_SPP: u32 = 1024;

/// Samples per pixel of each half in the first round.
pub const FIRST_ROUND_SPP: u32 = 4;

/// Where a progressive render stops.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseTarget {
    /// Relative rms noise of the image (over the kept pixels) to stop at,
    /// in (0, 1).
    pub noise: f64,
    /// Most samples per pixel, both halves together: even, at least
    /// `2 * FIRST_ROUND_SPP`.
    pub max_spp: u32,
}

impl Default for NoiseTarget {
    fn default() -> Self {
        NoiseTarget {
            noise: DEFAULT_NOISE_TARGET,
            max_spp: DEFAULT_MAX_SPP,
        }
    }
}

impl NoiseTarget {
    /// # Errors
    /// [`Error::InvalidParameter`] for a noise outside (0, 1) or a
    /// `max_spp` below `2 * FIRST_ROUND_SPP` or above [`MAX_SPP`].
    pub fn validate(&self) -> Result<()> {
        if !(self.noise > 0.0 && self.noise < 1.0) {
            return Err(Error::param(
                "noise target",
                format!("must be in (0, 1), got {}", self.noise),
            ));
        }
        let least = 2 * FIRST_ROUND_SPP;
        if self.max_spp < least || self.max_spp > MAX_SPP {
            return Err(Error::param(
                "max spp",
                format!("must be in {least}..={MAX_SPP}, got {}", self.max_spp),
            ));
        }
        Ok(())
    }
}

/// One round's outcome, for progress reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Round {
    /// Samples per pixel so far, both halves.
    pub spp: u32,
    /// The relative noise of the mean so far.
    pub noise: f64,
}

/// A progressive render's image and how far it went.
#[derive(Clone, Debug)]
pub struct Progressive {
    /// The mean of both halves.
    pub image: Image,
    /// Samples per pixel, both halves.
    pub spp: u32,
    /// The image's estimated relative noise.
    pub noise: f64,
    /// Whether `noise` reached the target (else `max_spp` stopped it).
    pub converged: bool,
    /// Every round, in order.
    pub rounds: Vec<Round>,
}

/// Sums of one half's images, weighted by their spp.
struct Half {
    sum: Vec<glam::DVec3>,
    spp: u32,
}

impl Half {
    fn add(&mut self, image: &Image, spp: u32) {
        for (s, p) in self.sum.iter_mut().zip(&image.pixels) {
            *s += p.as_dvec3() * f64::from(spp);
        }
        self.spp += spp;
    }

    fn mean(&self, width: u32, height: u32) -> Image {
        let n = f64::from(self.spp.max(1));
        Image {
            width,
            height,
            pixels: self.sum.iter().map(|s| (*s / n).as_vec3()).collect(),
        }
    }
}

/// Renders `cfg`'s image in rounds of two halves until its noise over the
/// `keep` pixels reaches `target`. `render(cfg)` renders one half-round:
/// `cfg.spp` samples per pixel with `cfg.seed`. `on_round` hears of every
/// round.
///
/// # Errors
/// A bad `target` or mask; whatever `render` returns.
pub fn render_to_noise(
    cfg: &CheckedRender,
    target: &NoiseTarget,
    keep: &[bool],
    render: &mut dyn FnMut(&CheckedRender) -> Result<Image>,
    on_round: &mut dyn FnMut(&Round),
) -> Result<Progressive> {
    target.validate()?;
    let pixels = (cfg.width as usize) * (cfg.height as usize);
    let empty = || Half {
        sum: vec![glam::DVec3::ZERO; pixels],
        spp: 0,
    };
    let (mut a, mut b) = (empty(), empty());
    let max_half = target.max_spp / 2;
    let mut rounds = Vec::new();
    let mut step = FIRST_ROUND_SPP;
    loop {
        let r = rounds.len() as u64;
        let mut half = cfg.clone();
        half.0.spp = step;
        a.add(&render(&half.with_seed(hash2(cfg.seed, 2 * r)))?, step);
        b.add(&render(&half.with_seed(hash2(cfg.seed, 2 * r + 1)))?, step);
        let (ia, ib) = (a.mean(cfg.width, cfg.height), b.mean(cfg.width, cfg.height));
        let image = mean_of(&ia, &ib);
        // A - (A + B) / 2 = (A - B) / 2: the noise of the mean.
        let noise = relative_rmse_masked(&ia, &image, keep)?;
        let round = Round {
            spp: 2 * a.spp,
            noise,
        };
        on_round(&round);
        rounds.push(round);
        let converged = noise <= target.noise;
        if converged || a.spp >= max_half {
            return Ok(Progressive {
                image,
                spp: 2 * a.spp,
                noise,
                converged,
                rounds,
            });
        }
        step = next_step(a.spp, noise, target.noise).min(max_half - a.spp);
    }
}

/// Samples per half for the next round: what `1 / sqrt(spp)` predicts
/// reaches `target` from `noise` at `held` samples, a tenth more, between
/// `held / 4` (at least 1) and `held`.
fn next_step(held: u32, noise: f64, target: f64) -> u32 {
    let need = f64::from(held) * (noise / target).powi(2) * 1.1 - f64::from(held);
    let (least, most) = ((held / 4).max(1), held);
    if need.is_finite() {
        (need.ceil() as u32).clamp(least, most)
    } else {
        most
    }
}

fn mean_of(a: &Image, b: &Image) -> Image {
    Image {
        width: a.width,
        height: a.height,
        pixels: a
            .pixels
            .iter()
            .zip(&b.pixels)
            .map(|(p, q)| (*p + *q) * 0.5)
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::RenderConfig;
    use glam::Vec3;

    /// A fake renderer: pixel value 1 plus a deterministic, seed-dependent
    /// deviation of rms `sigma / sqrt(spp)`.
    fn fake(sigma: f64) -> impl FnMut(&CheckedRender) -> Result<Image> {
        move |cfg: &CheckedRender| {
            let s = (sigma / f64::from(cfg.spp).sqrt()) as f32;
            let mut rng = crate::rng::Rng::new(cfg.seed);
            let pixels = (0..cfg.width * cfg.height)
                .map(|_| {
                    // Uniform in [-sqrt 3, sqrt 3]: unit variance.
                    let u = (2.0 * rng.next_f32() - 1.0) * 3f32.sqrt();
                    Vec3::splat(1.0 + s * u)
                })
                .collect();
            Ok(Image {
                width: cfg.width,
                height: cfg.height,
                pixels,
            })
        }
    }

    #[test]
    fn stops_once_the_noise_is_at_the_target_and_the_noise_is_right() {
        let cfg = RenderConfig::new(64, 64).check().unwrap();
        let keep = vec![true; 64 * 64];
        let target = NoiseTarget {
            noise: 0.01,
            max_spp: 4096,
        };
        let p = render_to_noise(&cfg, &target, &keep, &mut fake(0.3), &mut |_| {}).unwrap();
        assert!(p.converged);
        assert!(p.noise <= 0.01);
        // The true noise of the mean at spp samples is 0.3 / sqrt(spp).
        let truth = 0.3 / f64::from(p.spp).sqrt();
        assert!(
            (p.noise / truth - 1.0).abs() < 0.1,
            "{} vs {truth}",
            p.noise
        );
        // 1/sqrt(spp) predicts 900 spp; the rounds overshoot by at most 2x.
        assert!((800..=1800).contains(&p.spp), "{}", p.spp);
        assert!(p.rounds.windows(2).all(|w| w[1].spp > w[0].spp));
    }

    #[test]
    fn max_spp_stops_it_unconverged() {
        let cfg = RenderConfig::new(16, 16).check().unwrap();
        let keep = vec![true; 256];
        let target = NoiseTarget {
            noise: 1e-4,
            max_spp: 64,
        };
        let p = render_to_noise(&cfg, &target, &keep, &mut fake(0.3), &mut |_| {}).unwrap();
        assert!(!p.converged);
        assert_eq!(p.spp, 64);
    }

    #[test]
    fn same_settings_same_image() {
        let cfg = RenderConfig::new(16, 16).check().unwrap();
        let keep = vec![true; 256];
        let t = NoiseTarget::default();
        let p = render_to_noise(&cfg, &t, &keep, &mut fake(0.5), &mut |_| {}).unwrap();
        let q = render_to_noise(&cfg, &t, &keep, &mut fake(0.5), &mut |_| {}).unwrap();
        assert_eq!(p.image.pixels, q.image.pixels);
        assert_eq!(p.spp, q.spp);
    }

    #[test]
    fn bad_targets_are_refused() {
        for (noise, max_spp) in [
            (0.0, 64),
            (1.0, 64),
            (f64::NAN, 64),
            (0.1, 7),
            (0.1, MAX_SPP + 1),
        ] {
            assert!(NoiseTarget { noise, max_spp }.validate().is_err());
        }
    }

    #[test]
    fn the_step_is_bounded() {
        assert_eq!(next_step(8, 0.02, 0.01), 8);
        assert_eq!(next_step(8, 0.0101, 0.01), 2);
        assert_eq!(next_step(100, 0.011, 0.01), 34);
        assert_eq!(next_step(1, 0.5, 0.01), 1);
    }
}
