//! `adaptive-pm merge SHARD.apm... --out MAP.apm [--json]`: every shard of one
//! run into one map file, streamed (see `adaptive_pm::photon_file::merge`).

use adaptive_pm::output::{check_target, refuse_overwrite};
use adaptive_pm::photon_file::merge;
use anyhow::Context;
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `merge`.
#[derive(clap::Args, Debug)]
pub struct MergeArgs {
    /// The shards' photon files (every shard of the run, each once, any order).
    #[arg(required = true)]
    pub shards: Vec<PathBuf>,
    /// The merged map file.
    #[arg(long)]
    pub out: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: MergeArgs) -> anyhow::Result<()> {
    // Before reading anything: --out names no shard (by identity, not by
    // spelling) and can be written.
    let inputs: Vec<&std::path::Path> = args.shards.iter().map(PathBuf::as_path).collect();
    refuse_overwrite(&args.out, &inputs).context("--out")?;
    check_target(&args.out).context("--out")?;
    let t = Instant::now();
    let m = merge(&args.shards, &args.out)?;
    let merge_s = t.elapsed().as_secs_f64();
    let h = &m.header;
    let budget_bound = h.flags & adaptive_pm::photon_file::FLAG_BUDGET_BOUND != 0;
    if args.json {
        println!(
            "{}",
            json!({
                "shards": h.merged_from,
                "photons": h.photons,
                "emitted": h.emitted,
                "bytes": std::fs::metadata(&args.out).map(|m| m.len()).unwrap_or(0),
                "clamped": h.clamped,
                "budget_bound": budget_bound,
                "merge_s": merge_s,
                "checksum": format!("{:016x}", m.checksum),
                "embree_isa": adaptive_pm::isa::Isa::from_code(h.settings.embree_isa),
                "embree_version": adaptive_pm::isa::version_name(h.settings.embree_version),
                "math_variant": adaptive_pm::isa::MathVariant::from_code(h.settings.math_variant),
                "out": args.out,
            })
        );
        return Ok(());
    }
    println!(
        "merged {} shards: {} photons from {} emitted, {:.3} s",
        h.merged_from, h.photons, h.emitted, merge_s
    );
    if budget_bound {
        println!(
            "note: the memory budget bound in a shard: the map differs from an unbounded run's"
        );
    }
    println!("checksum       {:016x}", m.checksum);
    println!("wrote {}", args.out.display());
    Ok(())
}
