//! `hostctl experiment`: run the paper's experiments (release tests) on the device.

/// Arguments of `hostctl experiment`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `hostctl experiment`.
pub fn run(_args: &Args) -> anyhow::Result<()> {
    anyhow::bail!("hostctl experiment is not implemented yet")
}
