//! `hostctl profile check FILE`: checks a haptic profile file (`profiles/README.md`) against
//! what a tune verified on a device: a tune result (`--tune-json`, the output of `hostctl tune
//! --json`) or a fresh dry-run tune on the device the connection flags name (the built-in
//! virtual device runs fast). The file format, the lowering and the check are
//! `stiffwall_tune::profile`'s; this parses flags and prints.
//!
//! Exit codes: 0 every element passes, 1 the check fails, 2 the file, the flags or the tune
//! are refused (as every hostctl command's errors).

use crate::device::connect::ConnectArgs;
use crate::output::{emit, emit_json};
use anyhow::{anyhow, Context as _, Result};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use stiffwall_tune::profile::{self, Device, Envelope, ProfileFile};
use stiffwall_tune::{Outcome, Settings, TuneError};

/// Arguments of `hostctl profile`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    pub command: Command,
}

/// `hostctl profile` subcommands.
#[derive(Debug, clap::Subcommand)]
pub enum Command {
    /// Check a profile file against a device's verified stiffness (a tune's result).
    Check(CheckArgs),
}

/// Arguments of `hostctl profile check`.
#[derive(Debug, clap::Args)]
pub struct CheckArgs {
    /// The profile file (TOML; profiles/README.md).
    pub file: PathBuf,
    /// A tune result: the output of `hostctl tune --json` (its `tune` object), or the bare
    /// object. Without it, a dry-run tune runs on the device first.
    #[arg(long, value_name = "TUNE.json", conflicts_with_all = ["port", "device", "plant", "qemu", "board_emulator"])]
    pub tune_json: Option<PathBuf>,
    #[command(flatten)]
    pub connect: ConnectArgs,
    /// Print the report as JSON (with a fresh tune, its result under `tune`).
    #[arg(long)]
    pub json: bool,
}

/// Runs `hostctl profile`, with its own exit codes (module header).
pub fn main(a: &Args) -> ExitCode {
    match a.command {
        Command::Check(ref c) => match check(c) {
            Ok(true) => ExitCode::SUCCESS,
            Ok(false) => ExitCode::from(1),
            Err(e) => {
                eprintln!("error: {}", crate::cli_error::message(&e));
                ExitCode::from(2)
            }
        },
    }
}

/// `profile check`: whether every element passes.
///
/// # Errors
/// The file unreadable or refused, the tune JSON unreadable, the tune failed.
pub fn check(a: &CheckArgs) -> Result<bool> {
    let text = std::fs::read_to_string(&a.file)
        .with_context(|| format!("reading {}", a.file.display()))?;
    let named = |e: profile::ProfileError| anyhow!("{}: {e}", a.file.display());
    let file = ProfileFile::from_toml(&text).map_err(named)?;
    let (envelope, outcome) = match &a.tune_json {
        Some(path) => (envelope_of_file(path)?, None),
        None => {
            let (envelope, o) = fresh_tune(a, &file)?;
            (envelope, Some(o))
        }
    };
    let lowered = profile::lower(&file, &envelope.device).map_err(named)?;
    let report = profile::check(&lowered, &envelope);
    if a.json {
        let mut j = serde_json::json!({
            "file": a.file,
            "target": envelope.source,
            "check": report,
        });
        if let Some(o) = outcome {
            j["tune"] = serde_json::to_value(o)?;
        }
        emit_json(&j)?;
    } else {
        emit(&profile::render(&report))?;
    }
    Ok(report.pass)
}

/// The envelope of a saved tune result.
fn envelope_of_file(path: &Path) -> Result<Envelope> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let mut v: serde_json::Value = serde_json::from_str(&text)
        .with_context(|| format!("--tune-json {}: not JSON", path.display()))?;
    let target = v["target"].as_str().map(str::to_owned);
    let tune = match v.get_mut("tune") {
        Some(t) => t.take(),
        None => v,
    };
    let o: Outcome = serde_json::from_value(tune).with_context(|| {
        format!(
            "--tune-json {}: not a tune result (the output of `hostctl tune --json`, or its \
             `tune` object)",
            path.display()
        )
    })?;
    Ok(Envelope::from_outcome(
        &o,
        target.unwrap_or_else(|| path.display().to_string()),
    ))
}

/// A dry-run tune on the device of the connection flags (the virtual device fast), as
/// `hostctl tune --dry-run` runs it; the file is lowered for the device first, so a bad file
/// is refused before any test.
fn fresh_tune(a: &CheckArgs, file: &ProfileFile) -> Result<(Envelope, Outcome)> {
    let mut connect = a.connect.clone();
    if connect.port.is_none() && !connect.qemu && !connect.board_emulator {
        connect.fast = true;
    }
    let name = connect.describe();
    let mut client = connect.connect()?;
    let info = &client.info;
    let device = if info.counts_per_rev > 0 {
        Device {
            rotational: true,
            resolution: core::f64::consts::TAU / f64::from(info.counts_per_rev),
        }
    } else {
        Device {
            rotational: false,
            resolution: f64::from(info.resolution),
        }
    };
    profile::lower(file, &device).map_err(|e| anyhow!("{}: {e}", a.file.display()))?;
    crate::session::stop_on_ctrl_c();
    let cancel = stiffwall_client::Cancel::on_ctrl_c();
    let settings = Settings {
        dry_run: true,
        ..Settings::default()
    };
    let o = stiffwall_tune::tune(&mut client, &settings, &cancel, &mut |e| {
        eprintln!("tune: {e}");
    })
    .map_err(|e| match e {
        TuneError::Cancelled => anyhow!("interrupted; the device's config was left as it was"),
        e => anyhow!("tune failed: {e}"),
    })?;
    let u = profile::Units::of(o.params.rotational);
    let sig = profile::units::sig;
    eprintln!(
        "tune (dry run) on {name}: K = {} {} at B = {} {} ({}), margin ×{}, quiet ceiling {} {}",
        sig(o.k_set),
        u.stiffness,
        sig(o.b_set),
        u.damping,
        o.damper,
        sig(o.margin_used),
        sig(o.quiet_ceiling),
        u.stiffness
    );
    Ok((Envelope::from_outcome(&o, name), o))
}
