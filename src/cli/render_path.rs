//! `adaptive-pm render --integrator path`: the unbiased reference image.

use super::render_spp::{path_image_to_noise, SppOutcome};
use adaptive_pm::render::{
    render_path_with, CheckedRender, Image, NoiseTarget, PathHalves, PathPart, RenderConfig,
    ToneMap, View,
};
use serde_json::json;
use std::time::Instant;

/// `--integrator path`: the image from two independent halves, and its
/// noise; with `--spp auto`, in rounds until that noise reaches the target.
pub fn run_path(
    args: &super::render::RenderArgs,
    prepared: &adaptive_pm::embree::EmbreeScene,
    cfg: &CheckedRender,
    target: Option<&NoiseTarget>,
    pool: &rayon::ThreadPool,
) -> anyhow::Result<()> {
    let part = match cfg.view {
        View::Full => PathPart::Full,
        View::DirectOnly => PathPart::Direct,
        View::Map { .. } | View::Emitters => {
            anyhow::bail!("--visualize-map needs --integrator photon")
        }
    };
    let t = Instant::now();
    let (image, dropped, outcome) = match target {
        Some(t) => pool.install(|| path_image_to_noise(prepared, cfg, part, t))?,
        None => pool.install(|| fixed_spp(prepared, cfg, part))?,
    };
    let secs = t.elapsed().as_secs_f64();
    let spp = outcome.spp;
    let samples = u64::from(cfg.width) * u64::from(image.height) * u64::from(spp);
    super::render::warn_dropped(dropped, samples);
    super::render::write_image(&image, cfg, args)?;
    if let Some(p) = &args.png {
        image.write_png(
            p,
            ToneMap {
                exposure: args.exposure,
            },
        )?;
    }
    let m = image.mean();
    if args.json {
        println!(
            "{}",
            json!({"scene": args.scene, "integrator": "path", "width": args.width,
            "height": args.height, "spp": spp, "noise_estimate": outcome.noise.map(|n| n.0),
            "noise_target_reached": outcome.noise.map(|n| n.1), "render_s": secs, "dropped_samples": dropped,
            "mean_rgb": [m.x, m.y, m.z], "out": args.out})
        );
    } else {
        println!(
            "path on {}: render {secs:.3} s, mean RGB {:.4} {:.4} {:.4}",
            args.scene, m.x, m.y, m.z
        );
        super::render::print_noise(&outcome);
        println!("wrote {}", args.out.display());
    }
    Ok(())
}

/// A fixed spp: two halves of `spp / 2` each when `spp >= 2` (an odd spp
/// loses one), whose difference gives the noise printed.
fn fixed_spp(
    prepared: &adaptive_pm::embree::EmbreeScene,
    cfg: &CheckedRender,
    part: PathPart,
) -> anyhow::Result<(Image, u64, SppOutcome)> {
    if cfg.spp < 2 {
        let (image, stats) = render_path_with(prepared, cfg, part, &|_, _| {})?;
        let outcome = SppOutcome {
            spp: cfg.spp,
            noise: None,
        };
        return Ok((image, stats.dropped_samples, outcome));
    }
    let mut half: RenderConfig = (**cfg).clone();
    half.spp = cfg.spp / 2;
    let h = PathHalves::render(prepared, &half, part)?;
    eprintln!(
        "path tracer noise (two halves): {:.3} % rms of the mean",
        100.0 * h.noise_rel(None)
    );
    let outcome = SppOutcome {
        spp: half.spp * 2,
        noise: None,
    };
    Ok((h.mean(), h.dropped_samples, outcome))
}
