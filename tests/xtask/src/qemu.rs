//! `cargo xtask qemu [--bless]`: builds the QEMU board image and runs the QEMU scenarios.
//!
//! The scenarios live in `host/hostctl/tests/qemu.rs` (opt-in `#[ignore]` tests, so plain `cargo test`
//! needs no QEMU): each boots the image under `qemu-system-arm -serial pty` inside a timeout,
//! talks to it through hostctl's own serial client, ends it through semihosting exit, and
//! compares its transcript with `firmware/boards/qemu-an386/scenarios/<name>.expected`.
//! `--bless` rewrites the expected files from this run. Then the QEMU recording test of
//! `host/hostctl/tests/device_cmds.rs` runs on the same image. Each step fails when fewer tests ran
//! than it has.

use crate::firmware::{self, root, IMAGES};
use crate::toolchain;
use anyhow::{bail, Result};

/// Runs every QEMU scenario.
pub fn qemu(args: &[String]) -> Result<()> {
    let bless = args.iter().any(|a| a == "--bless");
    if let Some(bad) = args.iter().find(|a| *a != "--bless") {
        bail!("unknown argument {bad:?} for `cargo xtask qemu` (allowed: --bless)");
    }
    toolchain::ensure_qemu()?;
    let cross = toolchain::ensure_cross()?;
    let image = IMAGES
        .iter()
        .find(|i| i.name == "qemu-an386")
        .expect("the QEMU image is in the image table");
    let elf = firmware::build(cross, image, &[])?;
    let mut cmd = scenarios_command();
    cmd.env("STIFFWALL_QEMU_IMAGE", &elf);
    if bless {
        cmd.env("STIFFWALL_BLESS", "1");
    }
    crate::process::run_counting(&mut cmd, QEMU_SCENARIOS)?;
    // The QEMU recording of `host/hostctl/tests/device_cmds.rs`: recorded on the image, replayed bit
    // for bit through the host build of the servo core.
    let mut rec = crate::process::cargo();
    rec.args([
        "test",
        "-p",
        "stiffwall-host",
        "--test",
        "device_cmds",
        "--",
        "--ignored",
        "--exact",
        "qemu_recording_replays_bit_for_bit",
    ])
    .env("STIFFWALL_QEMU_IMAGE", &elf)
    .current_dir(root());
    crate::process::run_counting(&mut rec, 1)
}

/// The cargo command that runs the scenarios of `host/hostctl/tests/qemu.rs`, one at a time
/// (the target comes from the caller's environment variables).
pub fn scenarios_command() -> std::process::Command {
    let mut cmd = crate::process::cargo();
    cmd.args([
        "test",
        "-p",
        "stiffwall-host",
        "--test",
        "qemu",
        "--",
        "--ignored",
        "--test-threads=1",
    ])
    .current_dir(root());
    cmd
}

/// The scenarios of `host/hostctl/tests/qemu.rs` (all must run, here and on the emulated board).
pub const QEMU_SCENARIOS: usize = 7;
