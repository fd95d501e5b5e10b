//! `adaptive-pm bench cornell [--scene cornell-empty] [--n-sweep 1..200]
//! [--n-max 100000] ...`: the paper's experiments (docs/method.md, "The
//! experiments") on a Cornell box (default: the paper's scene, the built-in
//! empty box), written as CSV files, SVG/PNG figures and `claims.md`, with
//! the paper's claims checked in a table.

use crate::cli::common::{parse_estimator, AssetRootArgs, EmbreeArgs, ThreadArgs};
use adaptive_pm::analysis::Estimator;
use adaptive_pm::engine::config::DEFAULT_MAX_DEPTH;
use adaptive_pm::engine::Mode;
use adaptive_pm::experiments::claims::check_claims;
use adaptive_pm::experiments::cornell::{run_cornell, CornellConfig, SweepDensityTarget};
use adaptive_pm::experiments::output::{claims_table, write_outputs};
use adaptive_pm::experiments::sweep::parse_sweep;
use anyhow::Context;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde_json::json;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `bench cornell`.
#[derive(clap::Args, Debug)]
pub struct CornellArgs {
    /// The scene: `cornell-empty` (walls and light: the paper's scene),
    /// `cornell` (with both blocks), or a glTF file with one area light.
    #[arg(long, default_value = adaptive_pm::scene::BUILTIN_CORNELL_EMPTY)]
    pub scene: String,
    #[command(flatten)]
    pub assets: AssetRootArgs,
    /// Light exponents n: A..B (inclusive), A..B:STEP, or a list a,b,c.
    #[arg(long, default_value = "1..200")]
    pub n_sweep: String,
    /// N_MAX of every run (the paper: 100000).
    #[arg(long, default_value_t = adaptive_pm::engine::config::PAPER_N_MAX)]
    pub n_max: u64,
    /// Modes, comma-separated.
    #[arg(
        long,
        default_value = "classic,density,adaptive",
        value_delimiter = ','
    )]
    pub modes: Vec<Mode>,
    /// Seed of every run.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output folder (default `bench-out/cornell-<unix time>`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub threads: ThreadArgs,
    #[command(flatten)]
    pub embree: EmbreeArgs,
    /// Directionality estimator of the adaptive runs: paper or peak (both are reported).
    #[arg(long, default_value = "paper", value_parser = parse_estimator)]
    pub directionality: Estimator,
    /// Bounces after the first hit.
    #[arg(long, default_value_t = DEFAULT_MAX_DEPTH)]
    pub max_depth: u32,
    /// Density control's target: `max` (the reference's primary-map max
    /// density: the paper's reading, docs/method.md, "Density control"),
    /// `mean` (its full-map mean density) or photons per unit area.
    #[arg(long, default_value = "max")]
    pub density_target: SweepDensityTarget,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

fn sweep_bar(show: bool, total: usize) -> ProgressBar {
    if !show || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(total as u64), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template("{spinner} {msg:>22} [{bar:40}] {pos}/{len} runs ({eta})")
            .expect("static template")
            .progress_chars("=> "),
    );
    bar
}

pub fn run(args: CornellArgs) -> anyhow::Result<()> {
    let start = Instant::now();
    let mut modes = args.modes.clone();
    modes.dedup();
    let cfg = CornellConfig {
        scene: args.scene.clone(),
        asset_root: args.assets.asset_root.clone(),
        n_values: parse_sweep(&args.n_sweep)?,
        n_max: args.n_max,
        modes,
        seed: args.seed,
        estimator: args.directionality,
        max_depth: args.max_depth,
        density_target: args.density_target,
        embree_isa: args.embree.embree_isa,
    };
    cfg.validate()?;
    // A bad scene name fails here, before the output folder is made.
    adaptive_pm::scene::Scene::open_with(&cfg.scene, &cfg.load_options())
        .with_context(|| format!("--scene `{}`", cfg.scene))?;
    let out_dir = args.out.clone().unwrap_or_else(|| {
        let t = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs());
        PathBuf::from(format!("bench-out/cornell-{t}"))
    });
    // Fail before the sweep, not after minutes of tracing.
    std::fs::create_dir_all(&out_dir)
        .with_context(|| format!("cannot create the output folder {}", out_dir.display()))?;
    // Hook (issue 12): an exclusive probe, no planted symlink followed.
    adaptive_pm::output::probe(out_dir.join(".write-test"))
        .with_context(|| format!("the output folder {} is not writable", out_dir.display()))?;

    let pool = args.threads.pool()?;
    let bar = sweep_bar(!args.json, cfg.run_count());
    let results = pool.install(|| {
        run_cornell(&cfg, &|p| {
            bar.set_position(p.done as u64);
            bar.set_message(format!("n = {} {}", p.n, p.mode.name()));
        })
    })?;
    bar.finish_and_clear();
    write_outputs(&results, &out_dir)
        .with_context(|| format!("writing the results into {}", out_dir.display()))?;
    let elapsed = start.elapsed().as_secs_f64();

    if args.json {
        let value = json!({
            "scene": results.scene,
            "runs": results.runs,
            "reference": results.reference,
            "reference_max_density": results.reference_max_density(),
            "reference_max_density_primary_mesh": results.reference.max_density_primary_mesh,
            "reference_max_density_primary_at": results.reference.max_density_primary_at,
            "reference_sigma_density": results.reference_sigma_density(),
            "alpha": results.alpha,
            "claims": check_claims(&results),
            "timing": results.timing,
            "threads": pool.current_num_threads(),
            "elapsed_s": elapsed,
            "out_dir": out_dir,
        });
        println!("{value}");
        return Ok(());
    }
    println!(
        "Cornell sweep on `{}`: {} values of n ({}), modes {}, N_MAX = {}, seed {}, {} estimator, {} threads",
        results.scene,
        results.n_values.len(),
        args.n_sweep,
        results
            .modes
            .iter()
            .map(|m| m.name())
            .collect::<Vec<_>>()
            .join(","),
        results.n_max,
        results.seed,
        results.estimator,
        pool.current_num_threads()
    );
    let at = results.reference.max_density_primary_at;
    println!(
        "reference (classic, diffuse light): primary max density {:.4e} on `{}` at ({:.0}, {:.0}, {:.0}), full sigma {:.4e} photons/mm^2",
        results.reference_max_density(),
        results.reference.max_density_primary_mesh,
        at[0],
        at[1],
        at[2],
        results.reference_sigma_density()
    );
    println!();
    print!("{}", claims_table(&results));
    println!();
    println!("time per mode (s):   trace     kd-trees  densities  runs  photons emitted");
    for t in &results.timing {
        println!(
            "  {:<16} {:>8.2} {:>9.2} {:>10.2} {:>5}  {}",
            t.mode.map_or("", Mode::name),
            t.trace_s,
            t.build_s,
            t.measure_s,
            t.runs,
            t.emitted
        );
    }
    println!(
        "  analysis (both estimators, every n) {:.2} s",
        results.analysis_s
    );
    println!(
        "total {:.1} s: {} traces, {:.2} runs/s, {:.3e} photons emitted/s",
        elapsed,
        results.traces,
        results.traces as f64 / elapsed,
        results.photons_emitted() as f64 / elapsed
    );
    println!("files in {}", out_dir.display());
    Ok(())
}
