//! `adaptive-pm bench cornell` (in progress).

#[derive(clap::Args, Debug)]
pub struct CornellArgs {}

pub fn run(_args: CornellArgs) -> anyhow::Result<()> {
    anyhow::bail!("bench cornell is not implemented yet")
}
