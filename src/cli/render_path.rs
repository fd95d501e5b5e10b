//! `adaptive-pm render --integrator path`: the unbiased reference image.

use adaptive_pm::render::{render_path, PathHalves, PathPart, RenderConfig, ToneMap, View};
use serde_json::json;
use std::time::Instant;

/// `--integrator path`: the image from two independent halves, and its noise.
pub fn run_path(
    args: &super::render::RenderArgs,
    scene: &adaptive_pm::scene::Scene,
    rt: &adaptive_pm::embree::CommittedScene,
    cfg: &RenderConfig,
    pool: &rayon::ThreadPool,
) -> anyhow::Result<()> {
    let part = match cfg.view {
        View::Full => PathPart::Full,
        View::DirectOnly => PathPart::Direct,
        View::Map { .. } => anyhow::bail!("--visualize-map needs --integrator photon"),
    };
    let t = Instant::now();
    let image = if cfg.spp >= 2 {
        let mut half = cfg.clone();
        half.spp = cfg.spp / 2;
        let h = pool.install(|| PathHalves::render(scene, rt, &half, part))?;
        let noise = h.noise_rel(None);
        eprintln!(
            "path tracer noise (two halves): {:.3} % rms of the mean",
            100.0 * noise
        );
        h.mean()
    } else {
        pool.install(|| render_path(scene, rt, cfg, part, &|_, _| {}))?
    };
    let secs = t.elapsed().as_secs_f64();
    image.write_exr(&args.out)?;
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
            "height": args.height, "spp": cfg.spp, "render_s": secs,
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
