//! `adaptive-pm bench tradeoff` (in progress).

#[derive(clap::Args, Debug)]
pub struct TradeoffArgs {}

pub fn run(_args: TradeoffArgs) -> anyhow::Result<()> {
    anyhow::bail!("bench tradeoff is not implemented yet")
}
