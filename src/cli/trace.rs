//! `adaptive-pm trace <SCENE> --mode M (--quality Q | --n-max N)`: one run of
//! the engine, its counts, its maps' density statistics and timings.

use super::common::{
    open_scene, progress_bar, EmbreeArgs, SceneFileArgs, ThreadArgs, TraceConfigArgs,
};
use adaptive_pm::engine::counts::LightPlan;
use adaptive_pm::engine::{density_points, map_density, primary_density};
use adaptive_pm::engine::{Mode, TraceConfig, TraceReport, Tracer};
use adaptive_pm::photon_map::{DensityStats, PhotonMap};
use serde_json::json;

/// Arguments of `trace`.
#[derive(clap::Args, Debug)]
pub struct TraceArgs {
    /// A glTF file (.gltf or .glb), or a built-in scene: `cornell` (the Cornell
    /// box), `cornell-empty` (without its blocks), `cornell-glass` (with a mirror
    /// and a glass sphere instead), `door` (two rooms, a door ajar, the light in
    /// the room the camera does not see).
    pub scene: String,
    #[command(flatten)]
    pub assets: SceneFileArgs,
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
    let scene = open_scene(&args.scene, &args.assets, args.settings.cosn)?;
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
    let outcome = Outcome {
        args: &args,
        cfg: &cfg,
        report: &report,
        plans: &plans,
        full,
        primary,
        map: &map,
        build_s,
        peak_rss_bytes: peak_rss_bytes(),
        checksum,
        threads: pool.current_num_threads(),
    };
    if args.json {
        println!("{}", outcome.json());
    } else {
        outcome.print();
    }
    Ok(())
}

/// What a trace did, for its report.
struct Outcome<'a> {
    args: &'a TraceArgs,
    cfg: &'a TraceConfig,
    report: &'a TraceReport,
    plans: &'a [LightPlan],
    full: DensityStats,
    primary: DensityStats,
    map: &'a PhotonMap,
    build_s: f64,
    peak_rss_bytes: u64,
    checksum: u64,
    threads: usize,
}

impl Outcome<'_> {
    /// The `--json` object.
    fn json(&self) -> serde_json::Value {
        let mut v = self.base_json();
        // Only with --importance camera: the paper's runs print what they did.
        if let (Some(imp), Some(m)) = (&self.report.importance, v.as_object_mut()) {
            m.insert("importance".into(), json!(imp));
        }
        v
    }

    fn base_json(&self) -> serde_json::Value {
        let o = self;
        json!({
            "scene": o.args.scene,
            "mode": o.args.mode.name(),
            "n_max": o.report.n_max,
            "seed": o.cfg.seed,
            "threads": o.threads,
            "emitted": o.report.emitted,
            "emitted_per_light": o.report.emitted_per_light,
            "lights": o.plans,
            "stored": o.report.stored,
            "stored_primary": o.report.stored_primary,
            "reemitted_first_hit": o.report.reemitted_first_hit,
            "split_rate_by_depth": o.report.split_rate_by_depth,
            "depths": o.report.depths,
            "max_density": o.full.max,
            "mean_density": o.full.mean,
            "sigma_density": o.full.sigma,
            "sigma_over_mean": o.full.sigma_over_mean,
            "max_density_primary": o.primary.max,
            "mean_density_primary": o.primary.mean,
            "sigma_density_primary": o.primary.sigma,
            "sigma_over_mean_primary": o.primary.sigma_over_mean,
            "trace_s": o.report.trace_s,
            "rays": o.report.rays,
            "rays_per_s": o.report.rays_per_s,
            "peak_rss_bytes": o.peak_rss_bytes,
            "map_bytes": o.map.memory_bytes(),
            "trace_primary_s": o.report.trace_primary_s,
            "build_s": o.build_s,
            "bytes_per_photon": o.map.bytes_per_photon(),
            "budget_bound": o.report.budget_bound,
            "capped_hits": o.report.capped_hits,
            "density_rejected": o.report.density_rejected,
            "stored_power": o.report.stored_power,
            "shard": o.cfg.shard.to_string(),
            "checksum": format!("{:016x}", o.checksum),
            "embree_isa": o.report.kernels.map(|k| k.isa),
            "embree_version": o.report.kernels.map(|k| adaptive_pm::isa::version_name(k.version_code())),
            "math_variant": o.report.math,
        })
    }

    /// The text report.
    fn print(&self) {
        let o = self;
        println!(
            "{} on {}: N_MAX = {}, seed {}, {} threads",
            o.args.mode.name(),
            o.args.scene,
            o.report.n_max,
            o.cfg.seed,
            o.threads
        );
        for (i, p) in o.plans.iter().enumerate() {
            println!(
                "  light {i}: {} photons (alpha_E {:.3}, alpha_A {:.3}, alpha_D {:.4})",
                p.photons, p.alpha_e, p.alpha_a, p.alpha_d
            );
        }
        if let Some(imp) = &o.report.importance {
            println!(
                "importance     pass {:.3} s, {} cells, emission alpha_I {:?}, {} photons unread",
                imp.pass_s, imp.cells, imp.emission_alpha_i, imp.unread
            );
        }
        println!("emitted        {}", o.report.emitted);
        println!(
            "stored         {} ({} primary)",
            o.report.stored, o.report.stored_primary
        );
        println!(
            "re-emitted     {} after the first hit",
            o.report.reemitted_first_hit
        );
        let rates: Vec<String> = o
            .report
            .split_rate_by_depth
            .iter()
            .map(|x| format!("{x:.3}"))
            .collect();
        println!("split rate     {} (by depth)", rates.join(" "));
        println!(
            "density        max {:.4e}  mean {:.4e}  sigma {:.4e}  sigma/mean {:.3}",
            o.full.max, o.full.mean, o.full.sigma, o.full.sigma_over_mean
        );
        println!(
            "primary        max {:.4e}  mean {:.4e}  sigma {:.4e}  sigma/mean {:.3}",
            o.primary.max, o.primary.mean, o.primary.sigma, o.primary.sigma_over_mean
        );
        println!(
            "time           trace {:.3} s ({:.2} Mrays/s), kd-tree {:.3} s",
            o.report.trace_s, o.report.mrays_per_s, o.build_s
        );
        println!(
            "memory         {} bytes per photon, map {} MB, peak RSS {} MB",
            o.map.bytes_per_photon(),
            o.map.memory_bytes() >> 20,
            o.peak_rss_bytes >> 20
        );
        if o.report.budget_bound {
            println!("note: the memory budget bound (raise --budget-mb)");
        }
        if o.report.capped_hits > 0 {
            println!(
                "note: the per-hit split cap bound at {} hits",
                o.report.capped_hits
            );
        }
        let kernels = o.report.kernels.map_or("-".into(), |k| {
            format!(
                "{} of Embree {}",
                k.isa,
                adaptive_pm::isa::version_name(k.version_code())
            )
        });
        println!(
            "checksum       {:016x} (shard {}, Embree kernels {kernels})",
            o.checksum, o.cfg.shard
        );
    }
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
