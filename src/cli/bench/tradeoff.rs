//! `adaptive-pm bench tradeoff <SCENE>`: the speed/accuracy trade against a
//! path-traced reference (see `adaptive_pm::experiments::tradeoff`).

use super::super::common::{open_scene, EmbreeArgs, SceneFileArgs, ThreadArgs};
use adaptive_pm::engine::{Budget, Mode};
use adaptive_pm::experiments::tradeoff::knob::{choose_quality, Target};
use adaptive_pm::experiments::tradeoff::output::{summary_text, to_json, write_outputs};
use adaptive_pm::experiments::tradeoff::{run_tradeoff, Contender, TradeoffConfig};
use anyhow::Context;
use std::path::PathBuf;

/// Arguments of `bench tradeoff`.
#[derive(clap::Args, Debug)]
pub struct TradeoffArgs {
    /// A glTF file, `cornell`, or another built-in scene name.
    #[arg(default_value = "cornell")]
    pub scene: String,
    #[command(flatten)]
    pub assets: SceneFileArgs,
    /// N_MAX of each budget level (comma separated).
    #[arg(long, value_delimiter = ',', default_value = "10000,40000,160000")]
    pub n_max: Vec<u64>,
    /// Q values instead of N_MAX (comma separated); N_MAX = Q^2 (2^31 - 1).
    #[arg(long, value_delimiter = ',', conflicts_with = "n_max")]
    pub qualities: Option<Vec<f64>>,
    /// Contenders (comma separated): the three modes, and `importance`, the
    /// adaptive mode with `--importance camera` (its pass matched to the
    /// study's render, its time counted in the trace's).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "classic,density,adaptive,importance"
    )]
    pub modes: Vec<Contender>,
    /// Seeds per mode and budget (bias and variance are separated over them).
    #[arg(long, default_value_t = 3)]
    pub seeds: u32,
    /// Override every area light's cos^n exponent.
    #[arg(long, allow_negative_numbers = true, value_parser = crate::cli::common::parse_finite)]
    pub cosn: Option<f32>,
    /// Image width.
    #[arg(long, default_value_t = 32)]
    pub width: u32,
    /// Image height.
    #[arg(long, default_value_t = 32)]
    pub height: u32,
    /// Samples per pixel of the photon renders.
    #[arg(long, default_value_t = TradeoffConfig::default().spp)]
    pub spp: u32,
    /// Where the photon renders' gather directions come from at a diffuse
    /// surface: brdf (as the studies in docs/tradeoff/ were measured) or
    /// guided (the cache's guide, the renderer's default).
    #[arg(long, default_value = "brdf")]
    pub gather_directions: adaptive_pm::render::GatherDirections,
    /// Samples per pixel of each half of the path-traced reference.
    #[arg(long, default_value_t = TradeoffConfig::default().reference_spp)]
    pub reference_spp: u32,
    /// Fixed surface points of the irradiance error.
    #[arg(long, default_value_t = 128)]
    pub points: usize,
    /// Path-traced rays per point and half of the points' reference.
    #[arg(long, default_value_t = 4096)]
    pub point_samples: u32,
    /// Instead of the study: pick Q for a time target (seconds, adaptive mode).
    #[arg(long, conflicts_with = "target_error")]
    pub target_time: Option<f64>,
    /// Instead of the study: pick Q for an error target (relative, adaptive mode).
    #[arg(long)]
    pub target_error: Option<f64>,
    /// Output folder (created): JSON, CSVs, charts; the reference cache in its `cache/`.
    #[arg(long, default_value = "tradeoff-out")]
    pub out: PathBuf,
    #[command(flatten)]
    pub threads: ThreadArgs,
    #[command(flatten)]
    pub embree: EmbreeArgs,
    /// Print one JSON object on stdout (the progress and the summary go to stderr).
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: TradeoffArgs) -> anyhow::Result<()> {
    let scene = open_scene(&args.scene, &args.assets, args.cosn)?;
    let budgets: Vec<u64> = match &args.qualities {
        Some(qs) => qs
            .iter()
            .map(|&q| Budget::Quality(q).n_max())
            .collect::<Result<_, _>>()?,
        None => args.n_max.clone(),
    };
    let cfg = TradeoffConfig {
        budgets,
        modes: args.modes.clone(),
        seeds: args.seeds,
        width: args.width,
        height: args.height,
        spp: args.spp,
        reference_spp: args.reference_spp,
        points: args.points,
        point_samples: args.point_samples,
        cache_dir: Some(args.out.join("cache")),
        embree_isa: args.embree.embree_isa,
        gather_directions: args.gather_directions,
    };
    cfg.validate()?;
    std::fs::create_dir_all(args.out.join("cache"))
        .with_context(|| format!("creating {}", args.out.display()))?;
    let pool = args.threads.pool()?;
    let target = match (args.target_time, args.target_error) {
        (Some(t), _) => Some(Target::Time(t)),
        (_, Some(e)) => Some(Target::Error(e)),
        _ => None,
    };
    if let Some(target) = target {
        let device = args.embree.device()?;
        let prepared = std::sync::Arc::new(scene.commit(&device)?);
        let rc = cfg.render_config(cfg.spp, 1);
        let c = pool.install(|| choose_quality(&prepared, Mode::Adaptive, target, &rc))?;
        if args.json {
            println!("{}", serde_json::to_string(&c)?);
        } else {
            println!(
                "{target:?}: Q = {:.5} (N_MAX {}), predicted {:.3} s, estimated error {:.4}",
                c.quality, c.n_max, c.predicted_time_s, c.predicted_error
            );
        }
        return Ok(());
    }
    // Progress goes to stderr with --json too (the JSON is stdout's): a
    // study of several minutes said nothing to a log until it ended.
    let results = pool.install(|| {
        run_tradeoff(&args.scene, &scene, &cfg, &|p| {
            eprintln!("[{}/{}] {}", p.done, p.total, p.stage);
        })
    })?;
    write_outputs(&results, &args.out)?;
    let text = summary_text(&results);
    if args.json {
        eprint!("{text}");
        println!("{}", to_json(&results));
    } else {
        print!("{text}");
        println!(
            "{:.1} s on {} threads; wrote {}/{{tradeoff.json,runs.csv,groups.csv,*.svg,*.png}}",
            results.elapsed_s,
            results.threads,
            args.out.display()
        );
    }
    Ok(())
}
