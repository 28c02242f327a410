//! `cargo xtask fuzz [--frames N] [--seed S]`: the fuzz campaign of `firmware/tests/fuzz.rs`
//! (mutated frames against the decoder, hostile chunks into the firmware `Device` + `Servo`,
//! power cuts during config saves) and the end-to-end harness of `host/hostctl/tests/fuzz_pty.rs`
//! (garbage frames into the virtual device's pty while recording) with a chosen budget;
//! prints their counts.
//!
//! Units: N mutated frames (chunks N/10, power cuts N/100, pty frames N/10). `cargo test
//! --workspace` runs the same harnesses with their built-in short budgets (20 000 frames each);
//! `cargo xtask ci` then runs this campaign with N = 10⁷, seed 1 (docs/RELIABILITY.md's
//! figures; about 20 s on 2 cores).

use anyhow::{bail, Result};

/// Runs the campaign.
pub fn fuzz(args: &[String]) -> Result<()> {
    let mut frames: u64 = 1_000_000;
    let mut seed: u64 = 1;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let value = |v: Option<&String>, name: &str| -> Result<u64> {
            match v.and_then(|s| s.parse::<u64>().ok()) {
                Some(n) if (1..=10_000_000_000).contains(&n) => Ok(n),
                _ => bail!("{name} takes a whole number within [1, 1e10]"),
            }
        };
        match a.as_str() {
            "--frames" => frames = value(it.next(), "--frames")?,
            "--seed" => seed = value(it.next(), "--seed")?,
            other => {
                bail!("unknown argument {other:?}; usage: cargo xtask fuzz [--frames N] [--seed S]")
            }
        }
    }
    crate::process::run(
        crate::process::cargo()
            .args([
                "test",
                "-p",
                "stiffwall-firmware",
                "--test",
                "fuzz",
                "--",
                "--nocapture",
            ])
            .env("STIFFWALL_FUZZ_FRAMES", frames.to_string())
            .env("STIFFWALL_FUZZ_SEED", seed.to_string()),
    )?;
    crate::process::run(
        crate::process::cargo()
            .args([
                "test",
                "-p",
                "stiffwall-host",
                "--test",
                "fuzz_pty",
                "--",
                "--nocapture",
            ])
            .env(
                "STIFFWALL_FUZZ_PTY_FRAMES",
                (frames / 10).max(1).to_string(),
            )
            .env("STIFFWALL_FUZZ_SEED", seed.to_string()),
    )
}
