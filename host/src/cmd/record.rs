//! `hostctl record`: record telemetry losslessly to CSV.

/// Arguments of `hostctl record`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `hostctl record`.
pub fn run(_args: &Args) -> anyhow::Result<()> {
    anyhow::bail!("hostctl record is not implemented yet")
}
