//! `hostctl virtual`: serve the built-in virtual device on a pseudo-terminal for other tools.
//!
//! Units: as on a real board (the firmware core runs unchanged behind the pty). Invariants:
//! the pty's path is printed on standard output as the first line, `pty: /dev/pts/N`, flushed
//! before anything else happens, so a script can read it; the device runs (paced in real time,
//! or as fast as the client reads with `--fast`) until Ctrl-C (SIGINT), then stops cleanly.
//! Only the virtual device can be served: `--port` and `--qemu` are refused.

use crate::device::connect::ConnectArgs;
use crate::session;
use anyhow::{ensure, Context, Result};
use std::io::Write;
use std::time::Duration;

/// Arguments of `hostctl virtual`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Examples:\n  hostctl virtual --device phantom-1.0\n  hostctl virtual --fast &   # then: hostctl info --port /dev/pts/N"
)]
pub struct Args {
    /// The virtual device's plant (`--device NAME` or `--plant FILE.toml`) and pacing (`--fast`).
    #[command(flatten)]
    pub connect: ConnectArgs,
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
    drop(host);
    {
        let mut out = std::io::stdout().lock();
        writeln!(out, "pty: {}", vd.pty)?;
        out.flush()?;
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
