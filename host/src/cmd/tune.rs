//! `hostctl tune`: find and set the largest stable wall stiffness, with evidence.

/// Arguments of `hostctl tune`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `hostctl tune`.
pub fn run(_args: &Args) -> anyhow::Result<()> {
    anyhow::bail!("hostctl tune is not implemented yet")
}
