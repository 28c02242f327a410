//! `hostctl info`: show the connected device's identity, limits and latched faults.
//!
//! Units: SI as reported by the device (m or rad, N or N·m, Hz); counts and codes are raw
//! device integers. Read-only: nothing on the device changes.

use crate::device::connect::ConnectArgs;
use crate::output::{emit, emit_json, fault_names};
use anyhow::Result;
use std::fmt::Write as _;
use stiffwall_proto::{DeviceInfo, FaultReport};

/// Arguments of `hostctl info`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Examples:\n  hostctl info\n  hostctl info --port /dev/ttyACM0 --json")]
pub struct Args {
    /// How to reach the device.
    #[command(flatten)]
    pub connect: ConnectArgs,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// The text report of `hostctl info`.
#[must_use]
pub fn render(target: &str, d: &DeviceInfo, f: &FaultReport) -> String {
    let unit = if d.counts_per_rev > 0 {
        ("rad", "N·m")
    } else {
        ("m", "N")
    };
    let mut s = String::new();
    let _ = writeln!(s, "target:      {target}");
    let _ = writeln!(
        s,
        "firmware:    {} {} (protocol {})",
        d.firmware_name, d.firmware_version, d.protocol_version
    );
    let _ = writeln!(s, "board:       {}", d.board);
    let _ = writeln!(
        s,
        "servo rate:  {} Hz (T = {:.1} µs); allowed {}..={} Hz",
        d.servo_rate_hz,
        1e6 / f64::from(d.servo_rate_hz.max(1)),
        d.limits.min_rate_hz,
        d.limits.max_rate_hz
    );
    if d.counts_per_rev > 0 {
        let _ = writeln!(
            s,
            "encoder:     {} counts/rev, Δ = {:.6e} rad, {}-bit counter",
            d.counts_per_rev, d.resolution, d.encoder_bits
        );
    } else {
        let _ = writeln!(
            s,
            "encoder:     linear, Δ = {:.6e} m, {}-bit counter",
            d.resolution, d.encoder_bits
        );
    }
    let _ = writeln!(
        s,
        "force scale: {:.6e} {} per code, ±{} codes (±{:.4} {})",
        d.force_per_code, unit.1, d.max_code, d.limits.max_force, unit.1
    );
    let _ = writeln!(
        s,
        "limits:      K ≤ {} {}/{} at shift 0, extra delay ≤ {} ticks, coarsen shift ≤ {}",
        d.limits.max_stiffness,
        unit.1,
        unit.0,
        d.limits.max_delay_ticks,
        d.limits.max_coarsen_shift
    );
    let _ = writeln!(
        s,
        "telemetry:   {} samples per batch; excitation table {} entries",
        d.limits.telemetry_batch, d.limits.max_table
    );
    let _ = write!(
        s,
        "faults:      {}{}",
        fault_names(f.latched),
        if f.latched != 0 {
            format!(
                " (first at tick {}, safe mode {})",
                f.first_tick,
                if f.safe_mode { "on" } else { "off" }
            )
        } else {
            String::new()
        }
    );
    s
}

/// Runs `hostctl info`.
pub fn run(args: &Args) -> Result<()> {
    let mut c = args.connect.connect()?;
    let faults = c.faults()?;
    if args.json {
        let v = serde_json::json!({
            "target": args.connect.describe(),
            "device": c.info,
            "faults": {
                "latched": faults.latched,
                "names": fault_names(faults.latched),
                "first_tick": faults.first_tick,
                "safe_mode": faults.safe_mode,
            },
        });
        emit_json(&v)?;
    } else {
        emit(&render(&args.connect.describe(), &c.info, &faults))?;
    }
    Ok(())
}
