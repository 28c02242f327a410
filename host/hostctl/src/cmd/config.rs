//! `hostctl config`: read, change, save or reset the device's servo configuration.
//!
//! Units: SI (N/m or N·m/rad, N·s/m or N·m·s/rad, N or N·m, m/s or rad/s, J, Hz); ticks,
//! counts and shifts are integers. `set` reads the active config, changes only the fields
//! given, and sends it back; the device validates it and a refused config changes nothing
//! (the device's error names the field and its range). Obviously bad numbers (NaN, infinite,
//! negative, zero where a positive value is needed) are refused on the host before anything
//! is sent. Nothing is persisted unless `save` is run.

pub use crate::config_flags::{OnOff, Overrides, SafeModeArg, WallArg};
use crate::device::connect::ConnectArgs;
use crate::output::{config_table, emit, emit_json};
use anyhow::{bail, Context, Result};
use stiffwall_proto::ServoConfig;

/// Arguments of `hostctl config`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Examples:\n  hostctl config get --json\n  hostctl config set --stiffness 2.5 --delay-ticks 1\n  hostctl config set --damping 0.01 --damper dead-band-1\n  hostctl config set --rate 5000 --energy-monitor off\n  hostctl config save\n  hostctl config defaults\n\nThe built-in virtual device starts afresh with every hostctl run, so a `config set` on it\nlasts for that run only: `stream` and `record` take the same field flags (e.g.\n`hostctl record out.csv --stiffness 2 --rate 5000`)."
)]
pub struct Args {
    /// What to do.
    #[command(subcommand)]
    pub action: Action,
    /// How to reach the device.
    #[command(flatten)]
    pub connect: ConnectArgs,
    /// Print the resulting configuration as JSON.
    #[arg(long, global = true)]
    pub json: bool,
}

/// `config` actions.
#[derive(Debug, clap::Subcommand)]
pub enum Action {
    /// Print the active configuration.
    Get,
    /// Change the given fields of the active configuration (not persisted).
    Set(Overrides),
    /// Persist the active configuration to the device's config store.
    Save,
    /// Apply the firmware defaults (not persisted) and print them.
    Defaults,
}

/// Runs `hostctl config`.
pub fn run(args: &Args) -> Result<()> {
    if let Action::Set(o) = &args.action {
        // Refuse bad numbers before connecting.
        o.apply(&ServoConfig::default())?;
        if o.is_empty() {
            bail!(
                "config set: give at least one field to change (see `hostctl config set --help`)"
            );
        }
    }
    let mut c = args.connect.connect()?;
    let (cfg, what) = match &args.action {
        Action::Get => (c.get_config()?, None),
        Action::Set(o) => (
            o.set_on(&mut c).context("config set")?,
            Some("set (not saved)"),
        ),
        Action::Save => {
            c.save_config().context("config save")?;
            (c.get_config()?, Some("saved"))
        }
        Action::Defaults => (
            c.load_defaults().context("config defaults")?,
            Some("firmware defaults applied (not saved)"),
        ),
    };
    if args.json {
        emit_json(&cfg)?;
    } else {
        if let Some(w) = what {
            emit(&format!("# {w} on {}", args.connect.describe()))?;
        }
        emit(&config_table(&cfg, c.info.counts_per_rev > 0))?;
    }
    Ok(())
}
