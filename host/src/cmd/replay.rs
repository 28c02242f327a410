//! `hostctl replay`: replay a recording through the simulated plant and the firmware servo core.

/// Arguments of `hostctl replay`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `hostctl replay`.
pub fn run(_args: &Args) -> anyhow::Result<()> {
    anyhow::bail!("hostctl replay is not implemented yet")
}
