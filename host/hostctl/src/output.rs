//! Standard output of every `hostctl` command: one writer for tables and JSON reports.
//!
//! Units: none (text). Invariants: every report ends with exactly one newline (added when the
//! text lacks it); JSON is pretty-printed; a closed pipe (`hostctl info | head`) is not an
//! error, any other write failure is.

use serde::Serialize;
use std::fmt::Write as _;
use stiffwall_proto::{fault, SafeMode, ServoConfig, WallMode};

/// Why a report could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// Writing to standard output failed (other than a closed pipe).
    #[error("writing to standard output: {0}")]
    Stdout(#[from] std::io::Error),
    /// The report could not be serialised as JSON.
    #[error("serialising the report as JSON: {0}")]
    Json(#[from] serde_json::Error),
}

/// Prints `text` to stdout, followed by a newline unless it already ends with one.
///
/// # Errors
/// A write error other than a closed pipe.
pub fn emit(text: &str) -> Result<(), OutputError> {
    write_text(&mut std::io::stdout().lock(), text)
}

/// [`emit`] into any writer.
fn write_text(out: &mut impl std::io::Write, text: &str) -> Result<(), OutputError> {
    let newline: &[u8] = if text.ends_with('\n') { b"" } else { b"\n" };
    match out
        .write_all(text.as_bytes())
        .and_then(|()| out.write_all(newline))
        .and_then(|()| out.flush())
    {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        r => Ok(r?),
    }
}

/// Prints `value` as pretty JSON (one trailing newline).
///
/// # Errors
/// A serialisation or write error.
pub fn emit_json<T: Serialize + ?Sized>(value: &T) -> Result<(), OutputError> {
    emit(&serde_json::to_string_pretty(value)?)
}

/// Prints `value` as JSON when `json`, else the table `table(value)`.
///
/// # Errors
/// A serialisation or write error.
pub fn emit_report<T: Serialize + ?Sized>(
    json: bool,
    value: &T,
    table: impl FnOnce(&T) -> String,
) -> Result<(), OutputError> {
    if json {
        emit_json(value)
    } else {
        emit(&table(value))
    }
}

/// The machine names ([`fault::NAMES`], kebab-case: `energy-growth`, `travel`) of the fault
/// bits set in `bits`, in bit order; bits no name covers (a newer device's) as one
/// `unknown 0x…` entry. How every command prints a fault mask.
#[must_use]
pub fn fault_name_list(bits: u32) -> Vec<String> {
    let mut v: Vec<String> = fault::NAMES
        .iter()
        .filter(|(b, _, _)| bits & b != 0)
        .map(|(_, n, _)| (*n).to_string())
        .collect();
    let unknown = bits & !fault::ALL;
    if unknown != 0 {
        v.push(format!("unknown {unknown:#x}"));
    }
    v
}

/// [`fault_name_list`] joined with `, `, or `none` when no bit is set.
#[must_use]
pub fn fault_names(bits: u32) -> String {
    let v = fault_name_list(bits);
    if v.is_empty() {
        "none".into()
    } else {
        v.join(", ")
    }
}

/// `x` to 6 significant digits without trailing zeros (an f32 field set as 0.1 reads back as
/// 0.099999994 in full: "0.1").
#[must_use]
pub fn sig6(x: f32) -> String {
    let v = f64::from(x);
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let decimals = (5 - v.abs().log10().floor() as i32).clamp(0, 40) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Text rendering of a servo configuration, one `name value unit` row per field (the table of
/// `hostctl config get` and of the live view's config panel), in a rotary device's units
/// (N·m/rad, N·m·s/rad, N·m, rad/s) or a linear one's (N/m, N·s/m, N, m/s).
#[must_use]
pub fn config_table(c: &ServoConfig, rotary: bool) -> String {
    let (k, b, f, v) = if rotary {
        ("N·m/rad", "N·m·s/rad", "N·m", "rad/s")
    } else {
        ("N/m", "N·s/m", "N", "m/s")
    };
    let mut s = String::new();
    let travel_end = |end: Option<i32>| end.map_or_else(|| "off".into(), |n| format!("{n} counts"));
    let rows: [(&str, String); 19] = [
        ("stiffness", format!("{} {k}", sig6(c.stiffness))),
        ("damping", format!("{} {b}", sig6(c.damping))),
        ("damper", c.damper.to_string()),
        ("rate", format!("{} Hz", c.servo_rate_hz)),
        ("delay-ticks", c.extra_delay_ticks.to_string()),
        ("coarsen-shift", c.coarsen_shift.to_string()),
        (
            "wall",
            match c.wall {
                WallMode::Bidirectional => "bidirectional".into(),
                WallMode::OneSided => "one-sided".into(),
            },
        ),
        ("wall-position", format!("{} counts", c.wall_position)),
        ("force-limit", format!("{} {f}", sig6(c.force_limit))),
        (
            "max-velocity",
            if c.max_velocity > 0.0 {
                format!("{} {v}", sig6(c.max_velocity))
            } else {
                "off".into()
            },
        ),
        (
            "energy-monitor",
            if c.energy_monitor { "on" } else { "off" }.into(),
        ),
        ("energy-limit", format!("{} J", sig6(c.energy_limit))),
        ("energy-growth-cycles", c.energy_growth_cycles.to_string()),
        (
            "encoder-jump",
            format!("{} counts/tick", c.encoder_jump_counts),
        ),
        (
            "heartbeat-timeout-ms",
            if c.heartbeat_timeout_ms > 0 {
                c.heartbeat_timeout_ms.to_string()
            } else {
                "off".into()
            },
        ),
        (
            "safe-mode",
            match c.safe_mode {
                SafeMode::ZeroForce => "zero-force".into(),
                SafeMode::Damping => "damping".into(),
            },
        ),
        ("safe-damping", format!("{} {b}", sig6(c.safe_damping))),
        ("travel-min", travel_end(c.travel_min)),
        ("travel-max", travel_end(c.travel_max)),
    ];
    for (k, v) in rows {
        let _ = writeln!(s, "{k:<21} {v}");
    }
    s.pop();
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sig6_drops_the_f32_tail_and_keeps_six_digits() {
        assert_eq!(sig6(0.099_999_994), "0.1");
        assert_eq!(sig6(1.1), "1.1");
        assert_eq!(sig6(12_345.678), "12345.7");
        assert_eq!(sig6(5.4543e-3), "0.0054543");
        assert_eq!(sig6(0.0), "0");
        assert_eq!(sig6(-2.5), "-2.5");
    }

    #[test]
    fn a_config_reads_in_the_devices_units_only() {
        let c = ServoConfig {
            force_limit: 0.099_999_994,
            ..ServoConfig::default()
        };
        let rotary = config_table(&c, true);
        assert!(
            rotary.contains(" N·m/rad") && !rotary.contains(" N/m"),
            "{rotary}"
        );
        assert!(rotary.contains("force-limit           0.1 N·m"), "{rotary}");
        let linear = config_table(&c, false);
        assert!(
            linear.contains(" N/m") && !linear.contains("N·m"),
            "{linear}"
        );
    }

    struct Closed(std::io::ErrorKind);
    impl std::io::Write for Closed {
        fn write(&mut self, _: &[u8]) -> std::io::Result<usize> {
            Err(self.0.into())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn fault_masks_print_as_names() {
        assert_eq!(fault_names(0), "none");
        assert_eq!(fault_name_list(0), Vec::<String>::new());
        assert_eq!(
            fault_names(fault::TRAVEL | fault::ENERGY_GROWTH),
            "energy-growth, travel"
        );
        assert_eq!(
            fault_names(fault::ALL).split(", ").count(),
            fault::NAMES.len()
        );
        assert_eq!(
            fault_name_list(fault::BUZZ | 1 << 20 | 1 << 30),
            ["buzz", "unknown 0x40100000"]
        );
    }

    #[test]
    fn one_trailing_newline() {
        for (text, want) in [("a", "a\n"), ("a\n", "a\n"), ("", "\n"), ("a\nb", "a\nb\n")] {
            let mut v = Vec::new();
            write_text(&mut v, text).unwrap();
            assert_eq!(String::from_utf8(v).unwrap(), want);
        }
    }

    #[test]
    fn closed_pipe_is_not_an_error_other_failures_are() {
        assert!(write_text(&mut Closed(std::io::ErrorKind::BrokenPipe), "x").is_ok());
        let e = write_text(&mut Closed(std::io::ErrorKind::PermissionDenied), "x").unwrap_err();
        assert!(matches!(e, OutputError::Stdout(_)), "{e}");
    }
}
