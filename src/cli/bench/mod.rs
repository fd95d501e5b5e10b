//! `adaptive-pm bench ...`: measurements, one file per benchmark.

pub mod cornell;
pub mod rays;
pub mod render;
pub mod tradeoff;

use clap::Subcommand;

#[derive(Subcommand, Debug)]
pub enum BenchCommand {
    /// Closest-hit throughput on incoherent rays: raw Embree, the safe wrapper, batches.
    Rays(rays::RaysArgs),
    /// The paper's experiments on the Cornell box (Figs. 7a, 7b, 8, 9a, 9b).
    Cornell(cornell::CornellArgs),
    /// The photon render against the path tracer at equal error; bias; direct light.
    Render(render::RenderBenchArgs),
    /// Error against a converged reference versus time, per mode and quality.
    Tradeoff(tradeoff::TradeoffArgs),
}

pub fn run(cmd: BenchCommand) -> anyhow::Result<()> {
    match cmd {
        BenchCommand::Rays(a) => rays::run(a),
        BenchCommand::Cornell(a) => cornell::run(a),
        BenchCommand::Render(a) => render::run(a),
        BenchCommand::Tradeoff(a) => tradeoff::run(a),
    }
}
