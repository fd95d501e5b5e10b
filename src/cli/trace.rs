//! `adaptive-pm trace <SCENE> --mode M (--quality Q | --n-max N)`: one run of
//! the engine, its counts, its maps' density statistics and timings.

use super::common::{open_scene, progress_bar, BudgetArgs, ThreadArgs};
use adaptive_pm::embree::Device;
use adaptive_pm::engine::measure::{DENSITY_POINTS, DENSITY_POINTS_SEED};
use adaptive_pm::engine::{measure, Maps, Mode, TraceConfig, Tracer};
use serde_json::json;

/// Arguments of `trace`.
#[derive(clap::Args, Debug)]
pub struct TraceArgs {
    /// A glTF file (.gltf or .glb), or `cornell` for the built-in Cornell box.
    pub scene: String,
    /// classic (Markov chains), density (density control) or adaptive (the paper).
    #[arg(long, default_value = "adaptive")]
    pub mode: Mode,
    #[command(flatten)]
    pub budget: BudgetArgs,
    #[command(flatten)]
    pub threads: ThreadArgs,
    #[command(flatten)]
    pub shard: super::shard::ShardArgs,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: TraceArgs) -> anyhow::Result<()> {
    let scene = open_scene(&args.scene, args.budget.cosn)?;
    let mut cfg: TraceConfig = args.budget.config(args.mode)?;
    cfg.shard = args.shard.resolve()?;
    cfg.validate()?;
    let pool = args.threads.pool()?;
    let device = Device::new()?;
    let rt = scene.commit(&device)?;
    let mut tracer = Tracer::new(&scene, &rt);
    let bar = progress_bar(!args.json);
    let out = pool.install(|| {
        tracer.trace_with_progress(&cfg, &|p| {
            bar.set_length(p.total);
            bar.set_position(p.done);
            bar.set_message(format!("depth {}", p.depth));
        })
    })?;
    bar.finish_and_clear();
    let points = scene
        .surface_sampler()
        .points(DENSITY_POINTS, DENSITY_POINTS_SEED);
    let (maps, metrics) = pool.install(|| {
        let maps = Maps::build(&out.records);
        let metrics = measure(&maps, &points);
        (maps, metrics)
    });
    let checksum =
        pool.install(|| super::shard::checksum_and_write(&args.shard, &scene, &cfg, &out))?;
    let r = &out.report;
    let value = json!({
        "scene": args.scene,
        "mode": args.mode.name(),
        "n_max": r.n_max,
        "seed": cfg.seed,
        "threads": pool.current_num_threads(),
        "emitted": r.emitted,
        "emitted_per_light": r.emitted_per_light,
        "lights": out.plans,
        "stored": r.stored,
        "stored_primary": r.stored_primary,
        "reemitted_first_hit": r.reemitted_first_hit,
        "split_rate_by_depth": r.split_rate_by_depth,
        "depths": r.depths,
        "max_density": metrics.full.max,
        "mean_density": metrics.full.mean,
        "sigma_density": metrics.full.sigma,
        "sigma_over_mean": metrics.full.sigma_over_mean,
        "max_density_primary": metrics.primary.max,
        "mean_density_primary": metrics.primary.mean,
        "sigma_density_primary": metrics.primary.sigma,
        "sigma_over_mean_primary": metrics.primary.sigma_over_mean,
        "trace_s": r.trace_s,
        "rays": r.rays,
        "mrays_per_s": r.mrays_per_s,
        "trace_primary_s": r.trace_primary_s,
        "build_s": maps.build_s,
        "build_primary_s": maps.build_primary_s,
        "bytes_per_photon": metrics.bytes_per_photon,
        "budget_bound": r.budget_bound,
        "capped_hits": r.capped_hits,
        "density_rejected": r.density_rejected,
        "stored_power": r.stored_power,
        "shard": cfg.shard.to_string(),
        "checksum": format!("{checksum:016x}"),
    });
    if args.json {
        println!("{value}");
        return Ok(());
    }
    println!(
        "{} on {}: N_MAX = {}, seed {}, {} threads",
        args.mode.name(),
        args.scene,
        r.n_max,
        cfg.seed,
        pool.current_num_threads()
    );
    for (i, p) in out.plans.iter().enumerate() {
        println!(
            "  light {i}: {} photons (alpha_E {:.3}, alpha_A {:.3}, alpha_D {:.4})",
            p.photons, p.alpha_e, p.alpha_a, p.alpha_d
        );
    }
    println!("emitted        {}", r.emitted);
    println!("stored         {} ({} primary)", r.stored, r.stored_primary);
    println!(
        "re-emitted     {} after the first hit",
        r.reemitted_first_hit
    );
    let rates: Vec<String> = r
        .split_rate_by_depth
        .iter()
        .map(|x| format!("{x:.3}"))
        .collect();
    println!("split rate     {} (by depth)", rates.join(" "));
    println!(
        "density        max {:.4e}  mean {:.4e}  sigma {:.4e}  sigma/mean {:.3}",
        metrics.full.max, metrics.full.mean, metrics.full.sigma, metrics.full.sigma_over_mean
    );
    println!(
        "primary        max {:.4e}  mean {:.4e}  sigma {:.4e}  sigma/mean {:.3}",
        metrics.primary.max,
        metrics.primary.mean,
        metrics.primary.sigma,
        metrics.primary.sigma_over_mean
    );
    println!(
        "time           trace {:.3} s, kd-tree {:.3} s",
        r.trace_s, maps.build_s
    );
    println!(
        "memory         {:.0} bytes per photon",
        metrics.bytes_per_photon
    );
    if r.budget_bound {
        println!("note: the memory budget bound (raise --budget-mb)");
    }
    if r.capped_hits > 0 {
        println!(
            "note: the per-hit split cap bound at {} hits",
            r.capped_hits
        );
    }
    println!("checksum       {checksum:016x} (shard {})", cfg.shard);
    Ok(())
}
