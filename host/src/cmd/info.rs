//! `hostctl info`: show the connected device's identity and limits.

/// Arguments of `hostctl info`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `hostctl info`.
pub fn run(_args: &Args) -> anyhow::Result<()> {
    anyhow::bail!("hostctl info is not implemented yet")
}
