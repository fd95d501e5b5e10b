//! Subcommands, one file each.

pub mod analyze;

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
}

pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Analyze(a) => analyze::run(a),
    }
}
