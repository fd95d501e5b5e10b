//! Subcommands, one file each.

pub mod analyze;
pub mod assemble;
pub mod bench;
pub mod common;
pub mod merge;
pub mod render;
pub mod render_path;
pub mod render_spp;
pub mod scene;
pub mod shard;
pub mod trace;

use clap::{Parser, Subcommand};

/// Photon tracing whose photon counts are set by the scene.
#[derive(Parser, Debug)]
#[command(name = "adaptive-pm", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Analyse the directionality of a scene's emitters and BRDFs, or of named functions.
    Analyze(analyze::AnalyzeArgs),
    /// Print what a scene holds: triangles, meshes, materials, lights, bounds.
    Scene(scene::SceneArgs),
    /// Trace photons in one mode and report counts, density statistics and timings.
    Trace(trace::TraceArgs),
    /// Render an image: direct light by light sampling, indirect light from the photon map.
    Render(render::RenderArgs),
    /// Merge the photon files of every shard of a run into one map file.
    Merge(merge::MergeArgs),
    /// Stack the tiles of a render (render --tile I/N) into one image.
    Assemble(assemble::AssembleArgs),
    /// Benchmarks: ray throughput, the paper's Cornell experiments, the speed/accuracy trade.
    #[command(subcommand)]
    Bench(bench::BenchCommand),
}

pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Analyze(a) => analyze::run(a),
        Command::Scene(a) => scene::run(a),
        Command::Trace(a) => trace::run(a),
        Command::Render(a) => render::run(a),
        Command::Merge(a) => merge::run(a),
        Command::Assemble(a) => assemble::run(a),
        Command::Bench(c) => bench::run(c),
    }
}
