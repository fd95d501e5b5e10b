//! `adaptive-pm bench rays <SCENE>`: closest-hit throughput on incoherent rays
//! (origins area-uniform on the surfaces, cosine-distributed directions), three
//! ways in one run: raw embree-sys calls, the safe wrapper one ray at a time,
//! and the wrapper in batches; on one thread and on all threads.

use crate::cli::common::{EmbreeArgs, SceneFileArgs};
use adaptive_pm::embree::{measure_throughput, Throughput};
use serde_json::json;

/// The most rays a pass may have.
const MAX_RAYS: usize = 1 << 25;

/// Arguments of `bench rays`.
#[derive(clap::Args, Debug)]
pub struct RaysArgs {
    /// A glTF file, or `cornell`.
    pub scene: String,
    #[command(flatten)]
    pub assets: SceneFileArgs,
    /// Rays per pass (at most 2^25: the rays, 32 bytes each, and their
    /// packets stay within about 2 GB).
    #[arg(long, default_value_t = 2_000_000)]
    pub rays: usize,
    /// Seed of the rays.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[command(flatten)]
    pub embree: EmbreeArgs,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

fn row(t: &Throughput) -> serde_json::Value {
    json!({
        "threads": t.threads,
        "raw_mrays_per_s": t.raw_mrays_per_s,
        "single_mrays_per_s": t.single_mrays_per_s,
        "batch_mrays_per_s": t.batch_mrays_per_s,
    })
}

pub fn run(args: RaysArgs) -> anyhow::Result<()> {
    if args.rays == 0 || args.rays > MAX_RAYS {
        // 1e8 rays aborted on their 3.2 GB allocation under a 4 GB limit.
        anyhow::bail!(
            "--rays {} is outside 1..={MAX_RAYS}: a throughput pass needs no more",
            args.rays
        );
    }
    let scene = args.assets.open(&args.scene)?;
    let device = args.embree.device()?;
    let rt = scene.embree_geometry(&device)?;
    let eps = scene.ray_epsilon();
    let rays = scene
        .surface_sampler()
        .incoherent_rays(args.rays, args.seed, eps);
    let all = std::thread::available_parallelism().map_or(1, |n| n.get());
    let one = measure_throughput(&rt, &rays, 1)?;
    let many = measure_throughput(&rt, &rays, all)?;
    if args.json {
        let mut v = row(&many);
        v["scene"] = json!(args.scene);
        v["rays"] = json!(rays.len());
        v["embree_isa"] = json!(rt.isa());
        v["one_thread"] = row(&one);
        v["embree_version"] = json!(format!("{:?}", device.version()));
        println!("{v}");
        return Ok(());
    }
    let (a, b, c) = device.version();
    println!(
        "{} rays on {} (Embree {a}.{b}.{c}), best of {} passes",
        rays.len(),
        args.scene,
        adaptive_pm::embree::throughput::REPETITIONS
    );
    println!(
        "{:>8} {:>12} {:>12} {:>12} {:>10} {:>10}",
        "threads", "raw Mray/s", "single", "batch", "single/raw", "batch/raw"
    );
    for t in [&one, &many] {
        println!(
            "{:>8} {:>12.2} {:>12.2} {:>12.2} {:>10.3} {:>10.3}",
            t.threads,
            t.raw_mrays_per_s,
            t.single_mrays_per_s,
            t.batch_mrays_per_s,
            t.single_mrays_per_s / t.raw_mrays_per_s,
            t.batch_mrays_per_s / t.raw_mrays_per_s
        );
    }
    Ok(())
}
