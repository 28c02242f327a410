//! `hostctl config`: read, change, save or reset the device's servo configuration.

/// Arguments of `hostctl config`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `hostctl config`.
pub fn run(_args: &Args) -> anyhow::Result<()> {
    anyhow::bail!("hostctl config is not implemented yet")
}
