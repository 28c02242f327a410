//! `hostctl simulate`: simulate one scene file and write the trajectory as CSV.

/// Arguments of `hostctl simulate`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `hostctl simulate`.
pub fn run(_args: &Args) -> anyhow::Result<()> {
    anyhow::bail!("hostctl simulate is not implemented yet")
}
