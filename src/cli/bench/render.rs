//! `adaptive-pm bench render <SCENE>`: the photon render against the path
//! tracer at equal error, the bias against the photon count, and direct light
//! alone (see `adaptive_pm::experiments::render_study`). Times are from one run on one
//! thread pool: only their ratios mean anything on a shared machine.

use crate::cli::common::{open_scene, EmbreeArgs, SceneFileArgs, ThreadArgs};
use adaptive_pm::engine::{CausticBudget, Mode};
use adaptive_pm::experiments::render_study::{run_direct_study, run_study, StudyConfig};
use adaptive_pm::render::{GatherAllocation, GatherDirections, RenderConfig};
use serde_json::json;

/// Arguments of `bench render`.
#[derive(clap::Args, Debug)]
pub struct RenderBenchArgs {
    /// `cornell`, `cornell-empty`, `cornell-glass`, `door` or a glTF file.
    #[arg(default_value = "cornell")]
    pub scene: String,
    #[command(flatten)]
    pub assets: SceneFileArgs,
    /// Override every area light's cos^n exponent.
    #[arg(long, allow_negative_numbers = true, value_parser = crate::cli::common::parse_finite)]
    pub cosn: Option<f32>,
    /// Image side in pixels.
    #[arg(long, default_value_t = 256)]
    pub size: u32,
    /// Samples per pixel of the path-traced reference.
    #[arg(long, default_value_t = 4096)]
    pub reference_spp: u32,
    /// Samples per pixel of the path tracer's timed render.
    #[arg(long, default_value_t = 64)]
    pub path_spp: u32,
    /// Photon budgets (N_MAX), comma-separated (the default's 2e5 is the
    /// Cornell box's fastest at 256^2).
    #[arg(
        long,
        default_value = "100000,200000,300000,1000000",
        value_delimiter = ','
    )]
    pub n_max: Vec<u64>,
    /// Caustic passes to try with each budget, comma-separated: `auto` (the
    /// renderer's default, N_MAX caustic photons when the scene has mirrors
    /// or glass), a photon count, 0 for none.
    #[arg(long, default_value = "auto", value_delimiter = ',')]
    pub caustic_photons: Vec<CausticBudget>,
    /// Largest spp of a photon render.
    #[arg(long, default_value_t = 512)]
    pub max_spp: u32,
    /// Render every budget once at this spp (the bias sweep) instead of searching.
    #[arg(long)]
    pub fixed_spp: Option<u32>,
    /// relRMSE target.
    #[arg(long, default_value_t = 0.03)]
    pub target: f64,
    /// Also measure direct light alone at this spp.
    #[arg(long)]
    pub direct_spp: Option<u32>,
    /// Light samples (shadow rays) per camera sample of the photon render.
    #[arg(long, default_value_t = RenderConfig::new(1, 1).light_samples)]
    pub light_samples: u32,
    /// Final-gather rays per camera sample of the photon render (on average with --gather-allocation variance).
    #[arg(long, default_value_t = RenderConfig::new(1, 1).final_gather)]
    pub final_gather: u32,
    /// How the photon render spreads its gather rays: variance or uniform.
    #[arg(long, default_value = "variance")]
    pub gather_allocation: GatherAllocation,
    /// Where the photon render's gather directions come from at a diffuse
    /// surface: guided (the cache's guide) or brdf.
    #[arg(long, default_value = "guided")]
    pub gather_directions: GatherDirections,
    /// Photons per radiance estimate of the photon render (and its cache).
    #[arg(long, default_value_t = RenderConfig::new(1, 1).k)]
    pub k: usize,
    /// Photons per irradiance-cache sample of the photon render, 2 or more
    /// (0: the gather reads the k nearest photons).
    #[arg(long, default_value_t = RenderConfig::new(1, 1).cache_stride)]
    pub cache_stride: u32,
    /// Time the photon render at the target (each budget's fewest spp
    /// there, the fastest budget's) and the path tracer this many more
    /// times, one after the other, and report the median ratio (2: the
    /// median of three runs, the default: one run's ratio moves with the
    /// machine's drift).
    #[arg(long, default_value_t = 2)]
    pub reruns: u32,
    /// Seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[command(flatten)]
    pub threads: ThreadArgs,
    #[command(flatten)]
    pub embree: EmbreeArgs,
}

pub fn run(args: RenderBenchArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.target > 0.0 && args.target < 1.0,
        "target must be in (0, 1), got {}",
        args.target
    );
    let scene = open_scene(&args.scene, &args.assets, args.cosn)?;
    let device = args.embree.device()?;
    let tracer = adaptive_pm::engine::Tracer::new(scene.commit(&device)?);
    let pool = args.threads.pool()?;
    let mut render = RenderConfig::new(args.size, args.size);
    render.light_samples = args.light_samples;
    render.final_gather = args.final_gather;
    render.gather_allocation = args.gather_allocation;
    render.gather_directions = args.gather_directions;
    render.k = args.k;
    render.cache_stride = args.cache_stride;
    render.check()?;
    let cfg = StudyConfig {
        size: args.size,
        reference_spp: args.reference_spp,
        path_spp: args.path_spp,
        n_max: args.n_max.clone(),
        caustic: args.caustic_photons.clone(),
        max_spp: args.max_spp,
        target: args.target,
        mode: Mode::Adaptive,
        render,
        seed: args.seed,
        fixed_spp: args.fixed_spp,
        reruns: args.reruns,
    };
    let log = |s: &str| eprintln!("{s}");
    let result = pool.install(|| run_study(&tracer, &cfg, &log))?;
    if let Some(m) = result.median_ratio {
        eprintln!(
            "median over {} runs: photon / path = 1/{:.1}",
            1 + result.reruns.len(),
            1.0 / m
        );
    }
    let direct = match args.direct_spp {
        Some(spp) => Some(pool.install(|| run_direct_study(tracer.prepared(), &cfg, spp))?),
        None => None,
    };
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!(
        "{}",
        serde_json::to_string_pretty(&json!({
            "scene": args.scene, "cosn": args.cosn, "size": args.size,
            "threads": pool.current_num_threads(), "loadavg": load.trim(),
            "light_samples": args.light_samples,
            "final_gather": args.final_gather, "k": args.k,
            "cache_stride": args.cache_stride,
            "gather_allocation": args.gather_allocation.name(),
            "gather_directions": args.gather_directions.name(),
            "result": result, "direct": direct,
        }))?
    );
    Ok(())
}
