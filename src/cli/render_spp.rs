//! `render --spp N|auto`: a fixed sample count, or rounds until the image's
//! own noise reaches `--noise` (`adaptive_pm::render::progressive`).

use adaptive_pm::embree::EmbreeScene;
use adaptive_pm::render::progressive::{Round, FIRST_ROUND_SPP};
use adaptive_pm::render::{
    render_checked, render_halves_to_noise, render_path_with, render_progressive, CheckedRender,
    Image, NoiseTarget, PathPart, RenderMaps, RenderStats,
};
use std::str::FromStr;

/// `--spp`: samples per pixel, or `auto`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Spp {
    /// Rounds until the noise target (or `--max-spp`).
    Auto,
    /// This many samples per pixel.
    Fixed(u32),
}

impl FromStr for Spp {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if s == "auto" {
            return Ok(Spp::Auto);
        }
        match s.parse::<u32>() {
            Ok(n) if n > 0 => Ok(Spp::Fixed(n)),
            _ => Err(format!("expected a positive integer or `auto`, got `{s}`")),
        }
    }
}

/// What `--spp` came to.
#[derive(Clone, Copy, Debug)]
pub struct SppOutcome {
    /// Samples per pixel rendered.
    pub spp: u32,
    /// With `auto`: the estimated relative noise and whether it reached
    /// the target.
    pub noise: Option<(f64, bool)>,
}

/// The noise target of `--spp auto` from `--noise` and `--max-spp`, or
/// `None` for a fixed count (refusing those options then, and `auto` with
/// `--tile`: each tile would stop at its own spp).
pub fn noise_target(args: &super::render::RenderArgs) -> anyhow::Result<Option<NoiseTarget>> {
    match args.spp {
        Spp::Fixed(_) => {
            if args.noise.is_some() || args.max_spp.is_some() {
                anyhow::bail!("--noise and --max-spp go with --spp auto, not a fixed --spp");
            }
            Ok(None)
        }
        Spp::Auto => {
            if args.tile.is_some() {
                anyhow::bail!(
                    "--tile needs a fixed --spp (with `auto` each tile would stop at its own spp)"
                );
            }
            let d = NoiseTarget::default();
            let t = NoiseTarget {
                noise: args.noise.unwrap_or(d.noise),
                max_spp: args.max_spp.unwrap_or(d.max_spp),
            };
            t.validate()?;
            Ok(Some(t))
        }
    }
}

/// The spp the render settings start from: the fixed count, or the first
/// round's.
pub fn first_spp(spp: Spp) -> u32 {
    match spp {
        Spp::Fixed(n) => n,
        Spp::Auto => FIRST_ROUND_SPP,
    }
}

/// One line on stderr per round: long renders say how far they are.
fn say_round(target: &NoiseTarget) -> impl FnMut(&Round) + '_ {
    move |r: &Round| {
        eprintln!(
            "render: {} spp, noise {:.2} % (target {:.2} %)",
            r.spp,
            100.0 * r.noise,
            100.0 * target.noise
        )
    }
}

/// The photon render at the asked spp.
pub fn photon_image(
    prepared: &EmbreeScene,
    maps: Option<&RenderMaps>,
    cfg: &CheckedRender,
    target: Option<&NoiseTarget>,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> anyhow::Result<(Image, RenderStats, SppOutcome)> {
    let Some(t) = target else {
        let (image, stats) = render_checked(prepared, maps, None, cfg, progress)?;
        let spp = cfg.spp;
        return Ok((image, stats, SppOutcome { spp, noise: None }));
    };
    let (p, stats) = render_progressive(prepared, maps, cfg, t, progress, &mut say_round(t))?;
    let outcome = SppOutcome {
        spp: p.spp,
        noise: Some((p.noise, p.converged)),
    };
    Ok((p.image, stats, outcome))
}

/// The path tracer's image in rounds until the noise target: its dropped
/// samples summed over the rounds.
pub fn path_image_to_noise(
    prepared: &EmbreeScene,
    cfg: &CheckedRender,
    part: PathPart,
    target: &NoiseTarget,
) -> anyhow::Result<(Image, u64, SppOutcome)> {
    let mut dropped = 0;
    let mut half = |c: &CheckedRender| {
        let (image, s) = render_path_with(prepared, c, part, &|_, _| {})?;
        dropped += s.dropped_samples;
        Ok(image)
    };
    let p = render_halves_to_noise(prepared, cfg, target, &mut half, &mut say_round(target))?;
    let outcome = SppOutcome {
        spp: p.spp,
        noise: Some((p.noise, p.converged)),
    };
    Ok((p.image, dropped, outcome))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spp_parses_counts_and_auto_only() {
        assert_eq!("auto".parse::<Spp>(), Ok(Spp::Auto));
        assert_eq!("64".parse::<Spp>(), Ok(Spp::Fixed(64)));
        for bad in ["0", "-1", "Auto", "", "1.5"] {
            assert!(bad.parse::<Spp>().is_err(), "{bad}");
        }
    }
}
