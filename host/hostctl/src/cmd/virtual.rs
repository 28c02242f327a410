//! `hostctl virtual`: serve the built-in virtual device on a pseudo-terminal for other tools.
//!
//! Units: as on a real board (the firmware core runs unchanged behind the pty). Invariants:
//! the pty's path is printed on standard output as the first line, `pty: /dev/pts/N`, flushed
//! before anything else happens, so a script can read it; the device runs (paced in real time,
//! or as fast as the client reads with `--fast`) until Ctrl-C (SIGINT), then stops cleanly.
//! Only the virtual device can be served: `--port` and `--qemu` are refused.
//!
//! `--profile FILE` (a haptic profile, `profiles/README.md`; `--tune-json`, `--force-profile`):
//! the device starts rendering the profile in place of its config's wall. It is read, lowered
//! for the device and checked against `--tune-json` exactly as `hostctl ui --profile` does
//! (`cmd::profile::prepare`: without `--tune-json` it is lowered, not checked), then loaded
//! over the protocol (`SetProfile`, read back) before the pty's line is printed; the active
//! profile is named on standard error. A file the library refuses, a tune result of another
//! device, or a profile failing its check (unless `--force-profile`) ends the command with
//! exit code 2 before anything is printed on standard output: nothing is served.

use crate::device::connect::ConnectArgs;
use crate::session;
use anyhow::{ensure, Context, Result};
use std::io::Write;
use std::path::PathBuf;
use std::time::Duration;

/// Arguments of `hostctl virtual`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Examples:\n  hostctl virtual --device phantom-1.0\n  hostctl virtual --fast &   # then: hostctl info --port /dev/pts/N\n  hostctl virtual --device maxon-re35 --profile profiles/knob-24-detents.toml --tune-json tune.json"
)]
pub struct Args {
    /// The virtual device's plant (`--device NAME` or `--plant FILE.toml`) and pacing (`--fast`).
    #[command(flatten)]
    pub connect: ConnectArgs,
    /// A haptic profile file (TOML, profiles/README.md) the device starts with, lowered for it
    /// and checked as `hostctl ui --profile` checks it.
    #[arg(long, value_name = "FILE.toml")]
    pub profile: Option<PathBuf>,
    /// A tune result (the output of `hostctl tune --json`) to check --profile against; a
    /// profile that fails it is refused and nothing is served.
    #[arg(long, value_name = "TUNE.json", requires = "profile")]
    pub tune_json: Option<PathBuf>,
    /// Serve with a --profile that fails the check anyway (what fails is printed).
    #[arg(long, requires = "tune_json")]
    pub force_profile: bool,
}

/// Runs `hostctl virtual`.
///
/// # Errors
/// `--port`/`--qemu` given, an unknown device, or no pseudo-terminal.
pub fn run(args: &Args) -> Result<()> {
    ensure!(
        args.connect.port.is_none() && !args.connect.qemu,
        "hostctl virtual serves the built-in virtual device; --port and --qemu do not apply"
    );
    let spec = args
        .connect
        .virtual_spec()?
        .ok_or_else(|| anyhow::anyhow!("no virtual device to serve"))?;
    session::stop_on_ctrl_c();
    let (vd, host) = stiffwall_client::spawn_virtual_device(spec)?;
    // Keep the pty's host side open with a plain file (no exclusive lock, unlike the serial
    // port handle from `spawn`, which is closed) so it never hangs up between clients.
    let _keep_open = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(&vd.pty)
        .with_context(|| format!("opening {}", vd.pty))?;
    let active = match &args.profile {
        Some(file) => Some(load_profile(args, file, host)?),
        None => {
            drop(host);
            None
        }
    };
    {
        let mut out = std::io::stdout().lock();
        writeln!(out, "pty: {}", vd.pty)?;
        out.flush()?;
    }
    if let Some(a) = &active {
        eprintln!("{a}");
    }
    eprintln!(
        "serving the {} on {}; connect with `hostctl info --port {}`; Ctrl-C stops",
        args.connect.describe(),
        vd.pty,
        vd.pty
    );
    while !stiffwall_client::interrupted() {
        std::thread::sleep(Duration::from_millis(50));
    }
    eprintln!("stopped");
    Ok(())
}

/// `--profile`: prepared as `hostctl ui --profile` prepares it (read, lowered for the device,
/// checked against `--tune-json`), loaded on the device through `host` (its side of the pty,
/// closed after) and read back; a line naming the active profile and its check.
///
/// # Errors
/// The file, the tune result or the check refused (nothing loaded), the device refused the
/// profile, or it reads back another one.
fn load_profile(
    args: &Args,
    file: &std::path::Path,
    host: Box<dyn serialport::SerialPort>,
) -> Result<String> {
    let mut client = stiffwall_client::Client::connect(host, None)?;
    let l = crate::cmd::profile::prepare(
        file,
        args.tune_json.as_deref(),
        args.force_profile,
        &client.info,
    )?;
    let wire = l.lowered.wire();
    client
        .set_profile(&wire)
        .with_context(|| format!("--profile {}: loading it onto the device", file.display()))?;
    ensure!(
        client.get_profile()? == wire,
        "--profile {}: the device's active profile differs from the one sent",
        file.display()
    );
    let check = match &l.report {
        None => "not checked (no --tune-json)".to_string(),
        Some(r) if r.pass => format!("passes the check against {}", r.envelope.source),
        Some(r) => format!(
            "FAILS the check against {} (served anyway: --force-profile)",
            r.envelope.source
        ),
    };
    Ok(format!(
        "profile {} active ({}, {} wire element(s)): {check}",
        l.lowered.name,
        file.display(),
        wire.elements.len()
    ))
}
