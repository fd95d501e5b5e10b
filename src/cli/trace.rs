//! `adaptive-pm trace <SCENE> --mode M (--quality Q | --n-max N)`: one run of
//! the engine, its counts, its maps' density statistics and timings.

use super::common::{open_scene, progress_bar, EmbreeArgs, ThreadArgs, TraceConfigArgs};
use adaptive_pm::engine::{density_points, map_density, primary_density};
use adaptive_pm::engine::{Mode, TraceConfig, Tracer};
use serde_json::json;

/// Arguments of `trace`.
#[derive(clap::Args, Debug)]
pub struct TraceArgs {
    /// A glTF file (.gltf or .glb), or a built-in scene: `cornell` (the Cornell
    /// box), `cornell-empty` (without its blocks), `cornell-glass` (with a mirror
    /// and a glass sphere instead).
    pub scene: String,
    /// classic (Markov chains), density (density control) or adaptive (the paper).
    #[arg(long, default_value = "adaptive")]
    pub mode: Mode,
    #[command(flatten)]
    pub settings: TraceConfigArgs,
    #[command(flatten)]
    pub threads: ThreadArgs,
    #[command(flatten)]
    pub embree: EmbreeArgs,
    #[command(flatten)]
    pub shard: super::shard::ShardArgs,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: TraceArgs) -> anyhow::Result<()> {
    // Fail before any work: an --out that cannot be written, or is the scene.
    args.shard.check_out(std::path::Path::new(&args.scene))?;
    let scene = open_scene(&args.scene, args.settings.cosn)?;
    let mut cfg: TraceConfig = args.settings.config(args.mode)?;
    cfg.shard = args.shard.resolve()?;
    cfg.validate()?;
    let pool = args.threads.pool()?;
    let device = args.embree.device()?;
    let tracer = Tracer::new(scene.commit(&device)?);
    let scene = tracer.scene();
    let bar = progress_bar(!args.json);
    let out = pool.install(|| {
        tracer.trace_with_progress(&cfg, &|p| {
            bar.set_length(p.total);
            bar.set_position(p.done);
            bar.set_message(format!("depth {}", p.depth));
        })
    })?;
    bar.finish_and_clear();
    let points = density_points(scene);
    // One map, built in place over the traced photons: the primary
    // statistics count only its depth-0 photons (the same k nearest as a
    // map of them alone), so the peak memory is the map itself.
    let (report, plans) = (out.report.clone(), out.plans.clone());
    let (map, build_s, full, primary) = pool.install(|| {
        let t = std::time::Instant::now();
        let map = out.into_map();
        let build_s = t.elapsed().as_secs_f64();
        let full = map_density(&map, &points);
        let primary = primary_density(&map, &points);
        (map, build_s, full, primary)
    });
    let checksum =
        super::shard::checksum_and_write(&args.shard, scene, &cfg, &map, (&report, &plans))?;
    let peak_rss_bytes = peak_rss_bytes();
    let out = (report, plans);
    let r = &out.0;
    let value = json!({
        "scene": args.scene,
        "mode": args.mode.name(),
        "n_max": r.n_max,
        "seed": cfg.seed,
        "threads": pool.current_num_threads(),
        "emitted": r.emitted,
        "emitted_per_light": r.emitted_per_light,
        "lights": out.1,
        "stored": r.stored,
        "stored_primary": r.stored_primary,
        "reemitted_first_hit": r.reemitted_first_hit,
        "split_rate_by_depth": r.split_rate_by_depth,
        "depths": r.depths,
        "max_density": full.max,
        "mean_density": full.mean,
        "sigma_density": full.sigma,
        "sigma_over_mean": full.sigma_over_mean,
        "max_density_primary": primary.max,
        "mean_density_primary": primary.mean,
        "sigma_density_primary": primary.sigma,
        "sigma_over_mean_primary": primary.sigma_over_mean,
        "trace_s": r.trace_s,
        "rays": r.rays,
        "rays_per_s": r.rays_per_s,
        "peak_rss_bytes": peak_rss_bytes,
        "map_bytes": map.memory_bytes(),
        "trace_primary_s": r.trace_primary_s,
        "build_s": build_s,
        "bytes_per_photon": map.bytes_per_photon(),
        "budget_bound": r.budget_bound,
        "capped_hits": r.capped_hits,
        "density_rejected": r.density_rejected,
        "stored_power": r.stored_power,
        "shard": cfg.shard.to_string(),
        "checksum": format!("{checksum:016x}"),
        "embree_isa": r.kernels.map(|k| k.isa),
        "embree_version": r.kernels.map(|k| adaptive_pm::isa::version_name(k.version_code())),
        "math_variant": r.math,
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
    for (i, p) in out.1.iter().enumerate() {
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
        full.max, full.mean, full.sigma, full.sigma_over_mean
    );
    println!(
        "primary        max {:.4e}  mean {:.4e}  sigma {:.4e}  sigma/mean {:.3}",
        primary.max, primary.mean, primary.sigma, primary.sigma_over_mean
    );
    println!(
        "time           trace {:.3} s ({:.2} Mrays/s), kd-tree {:.3} s",
        r.trace_s, r.mrays_per_s, build_s
    );
    println!(
        "memory         {} bytes per photon, map {} MB, peak RSS {} MB",
        map.bytes_per_photon(),
        map.memory_bytes() >> 20,
        peak_rss_bytes >> 20
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
    let kernels = r.kernels.map_or("-".into(), |k| {
        format!(
            "{} of Embree {}",
            k.isa,
            adaptive_pm::isa::version_name(k.version_code())
        )
    });
    println!(
        "checksum       {checksum:016x} (shard {}, Embree kernels {kernels})",
        cfg.shard
    );
    Ok(())
}

/// The process's peak resident memory (`VmHWM` of /proc/self/status), in
/// bytes; 0 where the OS does not say.
fn peak_rss_bytes() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|kb| kb.parse::<u64>().ok())
        })
        .map_or(0, |kb| kb * 1024)
}
