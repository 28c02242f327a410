//! `cargo xtask flash BOARD [--features LIST]`: builds a real board's image (release) and runs
//! it through the board's own probe-rs runner: flash, reset, stay attached and print the RTT log
//! of a `defmt` build.
//!
//! The probe-rs command line is read from the `runner` of the board's `.cargo/config.toml`, so
//! the chip is named in one place. Without probe-rs on `PATH` this stops before building and
//! prints the one install command (see docs/toolchain.md). CI never flashes.

use crate::firmware::{self, Image};
use crate::toolchain;
use anyhow::{bail, Context, Result};
use std::process::Command;

/// A board that can be flashed: its crate, binary, and the features a build may select.
#[derive(Debug)]
struct Board {
    name: &'static str,
    dir: &'static str,
    bin: &'static str,
    /// Features of which exactly one must be selected.
    one_of: &'static [&'static str],
    /// Further optional features.
    optional: &'static [&'static str],
}

const BOARDS: &[Board] = &[Board {
    name: "nucleo-f446re",
    dir: "firmware/boards/nucleo-f446re",
    bin: "stiffwall-nucleo-f446re",
    one_of: &["dac", "pwm"],
    optional: &["defmt"],
}];

/// The one command that installs probe-rs.
pub const PROBE_RS_INSTALL: &str = "cargo install probe-rs-tools --locked";

/// Parsed `flash` arguments: the board and its feature list.
#[derive(Debug, PartialEq, Eq)]
struct Request {
    board: &'static str,
    features: Vec<String>,
}

fn board_names() -> String {
    BOARDS.iter().map(|b| b.name).collect::<Vec<_>>().join(", ")
}

fn parse(args: &[String]) -> Result<Request> {
    let usage = "usage: cargo xtask flash BOARD --features dac|pwm[,defmt]";
    let mut board = None;
    let mut features: Vec<String> = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let list = if a == "--features" {
            let value = it.next();
            Some(
                value
                    .context("--features needs a value (e.g. --features dac)")?
                    .as_str(),
            )
        } else {
            a.strip_prefix("--features=")
        };
        match list {
            Some(list) => features.extend(
                list.split([',', ' '])
                    .filter(|f| !f.is_empty())
                    .map(str::to_string),
            ),
            None if a.starts_with('-') => bail!("unknown option {a:?}; {usage}"),
            None if board.is_some() => bail!("more than one board given ({a:?}); {usage}"),
            None => board = Some(a.as_str()),
        }
    }
    let Some(name) = board else {
        bail!(
            "no board given (flashable boards: {}); {usage}",
            board_names()
        );
    };
    let Some(b) = BOARDS.iter().find(|b| b.name == name) else {
        bail!(
            "unknown board {name:?} (flashable boards: {})",
            board_names()
        );
    };
    for f in &features {
        if !b.one_of.contains(&f.as_str()) && !b.optional.contains(&f.as_str()) {
            bail!(
                "unknown feature {f:?} for {}: allowed exactly one of {:?}, plus any of {:?}",
                b.name,
                b.one_of,
                b.optional
            );
        }
    }
    let chosen = features
        .iter()
        .filter(|f| b.one_of.contains(&f.as_str()))
        .count();
    if chosen != 1 {
        bail!(
            "{} needs exactly one of the features {:?} (the force output your wiring has), got {chosen}; {usage}",
            b.name,
            b.one_of
        );
    }
    Ok(Request {
        board: b.name,
        features,
    })
}

/// The `runner` command of a board's `.cargo/config.toml`, split into words.
fn runner(config: &str) -> Option<Vec<String>> {
    let line = config
        .lines()
        .map(str::trim)
        .find(|l| l.starts_with("runner") && l.contains('='))?;
    let value = line.split_once('=')?.1.trim();
    let value = value.strip_prefix('"')?.strip_suffix('"')?;
    let words: Vec<String> = value.split_whitespace().map(str::to_string).collect();
    (!words.is_empty()).then_some(words)
}

/// Builds and flashes one board image.
pub fn flash(args: &[String]) -> Result<()> {
    let req = parse(args)?;
    let board = BOARDS
        .iter()
        .find(|b| b.name == req.board)
        .expect("parse returns a known board");
    let dir = firmware::root().join(board.dir);
    let config_path = dir.join(".cargo/config.toml");
    let config = std::fs::read_to_string(&config_path)
        .with_context(|| format!("reading {}", config_path.display()))?;
    let runner = runner(&config)
        .with_context(|| format!("no `runner = \"...\"` in {}", config_path.display()))?;
    if !toolchain::which(&runner[0]) {
        bail!(
            "{} is not installed (needed to flash {}); install it with: {PROBE_RS_INSTALL}",
            runner[0],
            board.name
        );
    }
    let cross = toolchain::ensure_cross()?;
    let image = Image {
        name: board.name,
        dir: board.dir,
        bin: board.bin,
        features: &[],
    };
    let features: Vec<&str> = req.features.iter().map(String::as_str).collect();
    let elf = firmware::build(cross, &image, &features)?;
    crate::process::run(
        Command::new(&runner[0])
            .args(&runner[1..])
            .arg(&elf)
            .current_dir(&dir),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(s: &str) -> Vec<String> {
        s.split_whitespace().map(str::to_string).collect()
    }

    #[test]
    fn parses_board_and_features() {
        let r = parse(&args("nucleo-f446re --features dac")).unwrap();
        assert_eq!(r.board, "nucleo-f446re");
        assert_eq!(r.features, ["dac"]);
        let r = parse(&args("--features=pwm,defmt nucleo-f446re")).unwrap();
        assert_eq!(r.features, ["pwm", "defmt"]);
    }

    #[test]
    fn refuses_what_it_cannot_flash() {
        let err = |s: &str| parse(&args(s)).unwrap_err().to_string();
        assert!(err("nucleo-f446re").contains("exactly one of"));
        assert!(err("nucleo-f446re --features dac,pwm").contains("got 2"));
        assert!(err("nucleo-f446re --features dac,usb").contains("\"usb\""));
        assert!(err("qemu-an386 --features dac").contains("unknown board"));
        assert!(err("--features dac").contains("no board"));
        assert!(err("nucleo-f446re --features").contains("needs a value"));
    }

    #[test]
    fn every_board_has_a_probe_rs_runner() {
        for b in BOARDS {
            let path = firmware::root().join(b.dir).join(".cargo/config.toml");
            let config = std::fs::read_to_string(&path).unwrap();
            let r = runner(&config).unwrap_or_else(|| panic!("no runner in {}", path.display()));
            assert_eq!(r[..2], ["probe-rs", "run"], "{}", path.display());
            assert!(r.iter().any(|w| w == "--chip"), "{}", path.display());
        }
    }
}
