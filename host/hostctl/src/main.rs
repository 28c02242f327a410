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
    /// Simulate one scene file and write the trajectory as CSV.
    Simulate(cmd::simulate::Args),
    /// Stability map over a (beta, sigma) grid (the paper's Fig. 6/7).
    Map(Box<cmd::map::Args>),
    /// Show the connected device's identity and limits.
    Info(cmd::info::Args),
    /// Read, change, save or reset the device's servo configuration.
    Config(cmd::config::Args),
    /// Show the device's latched faults by name (`faults clear` clears them).
    Faults(cmd::faults::Args),
    /// Show live telemetry from the device.
    Stream(cmd::stream::Args),
    /// Record telemetry losslessly to CSV.
    Record(cmd::record::Args),
    /// Replay a recording through the simulated plant and the firmware servo core.
    Replay(cmd::replay::Args),
    /// Run the paper's experiments (release tests) on the device.
    Experiment(cmd::experiment::Args),
    /// Find and set the largest stable wall stiffness, with evidence.
    Tune(cmd::tune::Args),
    /// Check a haptic profile file against a device's verified stiffness.
    Profile(cmd::profile::Args),
    /// Live view of the device in the browser (traces, (beta, sigma) plane, release, tune).
    #[cfg(feature = "ui")]
    Ui(cmd::ui::Args),
    /// Serve the virtual device on a pseudo-terminal (prints its path) until Ctrl-C.
    Virtual(cmd::r#virtual::Args),
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Analyze(a) => cmd::analyze::run(a),
        Command::Simulate(a) => cmd::simulate::run(a),
        Command::Map(a) => cmd::map::run(a),
        Command::Info(a) => cmd::info::run(a),
        Command::Config(a) => cmd::config::run(a),
        Command::Faults(a) => cmd::faults::run(a),
        Command::Stream(a) => cmd::stream::run(a),
        Command::Record(a) => cmd::record::run(a),
        Command::Replay(a) => cmd::replay::run(a),
        Command::Experiment(a) => cmd::experiment::run(a),
        Command::Tune(a) => cmd::tune::run(a),
        Command::Profile(a) => return cmd::profile::main(a),
        #[cfg(feature = "ui")]
        Command::Ui(a) => cmd::ui::run(a),
        Command::Virtual(a) => cmd::r#virtual::run(a),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", stiffwall_host::cli_error::message(&e));
            std::process::ExitCode::from(2)
        }
    }
}
