//! `adaptive-pm analyze` (in progress).

#[derive(clap::Args, Debug)]
pub struct AnalyzeArgs {}

pub fn run(_args: AnalyzeArgs) -> anyhow::Result<()> {
    anyhow::bail!("not yet implemented")
}
