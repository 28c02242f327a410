//! `cargo xtask`: orchestration that plain cargo can't do.
//!
//! - `ci`: everything CI runs (the README's test command): fmt, clippy, host tests, no_std checks
//!   for the Cortex-M target, firmware cross-builds with the size report, QEMU scenarios.
//! - `firmware [--update-size-report]`: builds every board image.
//! - `qemu [--bless]`: runs the QEMU scenarios against their expected transcripts.
use anyhow::{bail, Context, Result};
use std::process::Command;

mod firmware;
mod qemu;
mod toolchain;

/// Runs a command, echoing it, and fails when it fails.
pub fn run(cmd: &mut Command) -> Result<()> {
    eprintln!("xtask: running {cmd:?}");
    let status = cmd.status().with_context(|| format!("starting {cmd:?}"))?;
    if !status.success() {
        bail!("{cmd:?} failed with {status}");
    }
    Ok(())
}

/// A `cargo` command in the repository root.
pub fn cargo() -> Command {
    let mut c = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    c.current_dir(firmware::root());
    c
}

/// no_std crates that must build for the Cortex-M target.
const NO_STD_CRATES: &[(&str, &[&str])] = &[
    ("stiffwall-core", &[]),
    ("stiffwall-proto", &[]),
    ("stiffwall-firmware", &[]),
    ("stiffwall-sim", &["--no-default-features"]),
];

fn ci() -> Result<()> {
    let cross = toolchain::ensure_cross()?;
    run(cargo().args(["fmt", "--all", "--check"]))?;
    run(cargo().args([
        "clippy",
        "--workspace",
        "--all-targets",
        "--",
        "-D",
        "warnings",
    ]))?;
    if cross == toolchain::Cross::Rustup {
        for (krate, extra) in NO_STD_CRATES {
            run(cargo()
                .args(["check", "-p", krate, "--target", toolchain::TARGET])
                .args(*extra))?;
        }
    } else {
        eprintln!("xtask: no_std crates are checked through the board builds (build-std fallback)");
    }
    firmware::firmware(&[])?;
    run(cargo().args(["test", "--workspace"]))?;
    Ok(())
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("ci") => ci(),
        Some("firmware") => firmware::firmware(&args[1..]),
        Some("qemu") => qemu::qemu(&args[1..]),
        other => bail!("unknown xtask {other:?}; available: ci, firmware [--update-size-report], qemu [--bless]"),
    }
}
