//! `adaptive-pm render --integrator path`: the unbiased reference image.

use adaptive_pm::render::{render_path_with, PathHalves, PathPart, RenderConfig, ToneMap, View};
use serde_json::json;
use std::time::Instant;

/// `--integrator path`: the image from two independent halves, and its noise.
pub fn run_path(
    args: &super::render::RenderArgs,
    prepared: &adaptive_pm::embree::EmbreeScene,
    cfg: &RenderConfig,
    pool: &rayon::ThreadPool,
) -> anyhow::Result<()> {
    let part = match cfg.view {
        View::Full => PathPart::Full,
        View::DirectOnly => PathPart::Direct,
        View::Map { .. } => anyhow::bail!("--visualize-map needs --integrator photon"),
    };
    let t = Instant::now();
    let (image, dropped) = if cfg.spp >= 2 {
        let mut half = cfg.clone();
        half.spp = cfg.spp / 2;
        let h = pool.install(|| PathHalves::render(prepared, &half, part))?;
        let noise = h.noise_rel(None);
        eprintln!(
            "path tracer noise (two halves): {:.3} % rms of the mean",
            100.0 * noise
        );
        (h.mean(), h.dropped_samples)
    } else {
        let (image, stats) = pool.install(|| render_path_with(prepared, cfg, part, &|_, _| {}))?;
        (image, stats.dropped_samples)
    };
    let secs = t.elapsed().as_secs_f64();
    // Two halves of spp / 2 each when spp >= 2 (an odd spp loses one).
    let spp = if cfg.spp >= 2 {
        cfg.spp / 2 * 2
    } else {
        cfg.spp
    };
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
            "height": args.height, "spp": cfg.spp, "render_s": secs, "dropped_samples": dropped,
            "mean_rgb": [m.x, m.y, m.z], "out": args.out})
        );
    } else {
        println!(
            "path on {}: render {secs:.3} s, mean RGB {:.4} {:.4} {:.4}",
            args.scene, m.x, m.y, m.z
        );
        println!("wrote {}", args.out.display());
    }
    Ok(())
}
