//! `hostctl map`: stability map over a (beta, sigma) grid (the paper's Fig. 6/7).

/// Arguments of `hostctl map`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `hostctl map`.
pub fn run(_args: &Args) -> anyhow::Result<()> {
    anyhow::bail!("hostctl map is not implemented yet")
}
