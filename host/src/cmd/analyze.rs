//! `hostctl analyze`: the paper's analysis of one device.

/// Arguments of `hostctl analyze`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `hostctl analyze`.
pub fn run(_args: &Args) -> anyhow::Result<()> {
    anyhow::bail!("hostctl analyze is not implemented yet")
}
