//! `hostctl faults`: the device's latched faults by name, with the servo tick at which the
//! first of them latched and whether the device is in safe mode; `hostctl faults clear` clears
//! them (the device leaves safe mode) and says what was cleared.
//!
//! Units: servo ticks (the device's tick counter); fault names are `stiffwall_proto::fault`'s
//! machine names (`energy-growth`, `travel`, …). Invariants: `faults` only reads (exit 0
//! whatever is latched); `faults clear` fails (exit 2) when a fault latches again at once,
//! because its cause persists (a count outside the travel window, a wall the device cannot
//! hold), naming the faults; the device keeps one first tick for all latched faults.

use crate::device::connect::ConnectArgs;
use crate::output::{emit, emit_json, fault_name_list, fault_names};
use anyhow::{bail, Context, Result};
use std::fmt::Write as _;
use std::time::{Duration, Instant};
use stiffwall_client::Client;
use stiffwall_proto::{fault, FaultReport};

/// Arguments of `hostctl faults`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Examples:\n  hostctl faults --port /dev/ttyACM0\n  hostctl faults --json\n  hostctl faults clear --port /dev/ttyACM0\n\nFault names: energy-growth, energy-limit, over-velocity, heartbeat, encoder-jump, buzz,\ntravel (the raw count left the travel window, `config set --travel-min/--travel-max`).\nThe built-in virtual device starts afresh with every hostctl run (no faults): to look at\none over several commands, serve it with `hostctl virtual` and pass its `--port`."
)]
pub struct Args {
    /// Without an action: print the latched faults.
    #[command(subcommand)]
    pub action: Option<Action>,
    /// How to reach the device.
    #[command(flatten)]
    pub connect: ConnectArgs,
    /// Print JSON instead of text.
    #[arg(long, global = true)]
    pub json: bool,
}

/// `faults` actions.
#[derive(Debug, Clone, Copy, clap::Subcommand)]
pub enum Action {
    /// Clear the latched faults (the device leaves safe mode) and print what was cleared;
    /// fails when a fault latches again at once (its cause persists).
    Clear,
}

/// How long `faults clear` watches for faults latching again (the servo takes the clear on
/// its next tick; a cause that persists latches on the tick after).
const RELATCH_WATCH: Duration = Duration::from_millis(200);

/// The labels for people ([`fault::NAMES`]' third column) of the bits set in `bits`.
fn labels(bits: u32) -> Vec<&'static str> {
    fault::NAMES
        .iter()
        .filter(|(b, _, _)| bits & b != 0)
        .map(|(_, _, label)| *label)
        .collect()
}

/// One fault per line: its machine name and its label, e.g. `  travel         outside travel`.
fn fault_lines(bits: u32) -> String {
    let mut s = String::new();
    for (b, name, label) in fault::NAMES {
        if bits & b != 0 {
            let _ = writeln!(s, "  {name:<14} {label}");
        }
    }
    let unknown = bits & !fault::ALL;
    if unknown != 0 {
        let _ = writeln!(
            s,
            "  unknown {unknown:#x} (bits this hostctl has no name for)"
        );
    }
    s
}

/// The text report of `hostctl faults`.
#[must_use]
pub fn render(target: &str, f: &FaultReport) -> String {
    let mut s = String::new();
    if f.latched == 0 {
        let _ = write!(
            s,
            "no faults latched on the {target} (safe mode {})",
            on_off(f.safe_mode)
        );
        return s;
    }
    let _ = writeln!(
        s,
        "faults latched on the {target}: {} (first at tick {}, safe mode {})",
        fault_names(f.latched),
        f.first_tick,
        on_off(f.safe_mode)
    );
    s.push_str(&fault_lines(f.latched));
    s
}

/// The text report of `hostctl faults clear`: what was latched `before`, and the safe mode
/// `after`.
#[must_use]
pub fn render_cleared(target: &str, before: &FaultReport, after: &FaultReport) -> String {
    let mut s = String::new();
    if before.latched == 0 {
        let _ = write!(
            s,
            "nothing to clear on the {target}: no faults latched (safe mode {})",
            on_off(after.safe_mode)
        );
        return s;
    }
    let _ = writeln!(
        s,
        "cleared on the {target}: {} (first at tick {}); safe mode {}",
        fault_names(before.latched),
        before.first_tick,
        on_off(after.safe_mode)
    );
    s.push_str(&fault_lines(before.latched));
    s
}

fn on_off(b: bool) -> &'static str {
    if b {
        "on"
    } else {
        "off"
    }
}

/// A fault report as JSON: the bits, their names and labels, the first tick, safe mode.
fn report_json(f: &FaultReport) -> serde_json::Value {
    serde_json::json!({
        "latched": f.latched,
        "names": fault_name_list(f.latched),
        "labels": labels(f.latched),
        "first_tick": f.first_tick,
        "safe_mode": f.safe_mode,
    })
}

/// Clears the latched faults and watches them for [`RELATCH_WATCH`]: the servo takes the
/// clear on its next tick (until then the device still reports the old faults), and a cause
/// that persists latches them again on the tick after, with a new first tick. Returns the
/// reports from before the clear and from the end of the watch.
///
/// # Errors
/// A link error, or faults (named) still or again latched at the end of the watch.
fn clear(c: &mut Client) -> Result<(FaultReport, FaultReport)> {
    let before = c.faults().context("reading the faults")?;
    c.clear_faults().context("clearing the faults")?;
    let deadline = Instant::now() + RELATCH_WATCH;
    let after = loop {
        let f = c
            .faults()
            .context("reading the faults after clearing them")?;
        let relatched =
            f.latched != 0 && (before.latched == 0 || f.first_tick != before.first_tick);
        if relatched || Instant::now() > deadline {
            break f;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    if after.latched != 0 {
        bail!(
            "the faults latched again at once ({}, at tick {}): their cause persists (a count \
             outside the travel window, a wall the device cannot hold); bring the device back \
             or change the config (`hostctl config set`), then clear again",
            fault_names(after.latched),
            after.first_tick
        );
    }
    Ok((before, after))
}

/// Runs `hostctl faults`.
///
/// # Errors
/// No device, a link error, or (`clear`) faults that latch again at once.
pub fn run(args: &Args) -> Result<()> {
    let mut c = args.connect.connect()?;
    let target = args.connect.describe();
    match args.action {
        None => {
            let f = c.faults().context("reading the faults")?;
            if args.json {
                let mut v = report_json(&f);
                v["target"] = target.into();
                emit_json(&v)?;
            } else {
                emit(&render(&target, &f))?;
            }
        }
        Some(Action::Clear) => {
            let (before, after) = clear(&mut c)?;
            if args.json {
                emit_json(&serde_json::json!({
                    "target": target,
                    "cleared": report_json(&before),
                    "now": report_json(&after),
                }))?;
            } else {
                emit(&render_cleared(&target, &before, &after))?;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reports_name_every_fault_with_the_first_tick() {
        let f = FaultReport {
            latched: fault::TRAVEL | fault::ENCODER_JUMP,
            first_tick: 5123,
            safe_mode: true,
        };
        let t = render("virtual device", &f);
        assert_eq!(
            t,
            "faults latched on the virtual device: encoder-jump, travel (first at tick 5123, \
             safe mode on)\n  encoder-jump   encoder jump\n  travel         outside travel\n"
        );
        let none = FaultReport {
            latched: 0,
            first_tick: 0,
            safe_mode: false,
        };
        assert_eq!(
            render("x", &none),
            "no faults latched on the x (safe mode off)"
        );
        assert!(render_cleared("x", &f, &none).starts_with(
            "cleared on the x: encoder-jump, travel (first at tick 5123); safe mode off\n"
        ));
        assert_eq!(
            render_cleared("x", &none, &none),
            "nothing to clear on the x: no faults latched (safe mode off)"
        );
        let v = report_json(&f);
        assert_eq!(v["names"], serde_json::json!(["encoder-jump", "travel"]));
        assert_eq!(
            v["labels"],
            serde_json::json!(["encoder jump", "outside travel"])
        );
        assert_eq!(v["first_tick"], 5123);
        // A bit this hostctl does not know is shown, not dropped.
        let newer = render(
            "x",
            &FaultReport {
                latched: 1 << 12,
                ..f
            },
        );
        assert!(newer.contains("unknown 0x1000"), "{newer}");
    }
}
