//! `hostctl`: command-line front end of stiffwall.

use clap::{Parser, Subcommand};
use stiffwall_host::cmd;

/// Render the stiffest stable virtual wall, and show why it is stable.
#[derive(Debug, Parser)]
#[command(name = "hostctl", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Analyse a device: dimensionless parameters, stability region, stiffness limits.
    Analyze(cmd::analyze::Args),
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Analyze(a) => cmd::analyze::run(a),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::from(2)
        }
    }
}
