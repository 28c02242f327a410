//! `hostctl stream`: show live telemetry from the device.

/// Arguments of `hostctl stream`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `hostctl stream`.
pub fn run(_args: &Args) -> anyhow::Result<()> {
    anyhow::bail!("hostctl stream is not implemented yet")
}
