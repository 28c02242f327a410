//! Standard output of every `hostctl` command: one writer for tables and JSON reports.
//!
//! Units: none (text). Invariants: every report ends with exactly one newline (added when the
//! text lacks it); JSON is pretty-printed; a closed pipe (`hostctl info | head`) is not an
//! error, any other write failure is.

use serde::Serialize;
use std::fmt::Write as _;
use stiffwall_proto::{SafeMode, ServoConfig, WallMode};

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

/// Text rendering of a servo configuration, one `name value unit` row per field (the table of
/// `hostctl config get` and of the live view's config panel).
#[must_use]
pub fn config_table(c: &ServoConfig) -> String {
    let mut s = String::new();
    let rows: [(&str, String); 17] = [
        ("stiffness", format!("{} N/m (N·m/rad)", c.stiffness)),
        ("damping", format!("{} N·s/m (N·m·s/rad)", c.damping)),
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
        ("force-limit", format!("{} N (N·m)", c.force_limit)),
        (
            "max-velocity",
            if c.max_velocity > 0.0 {
                format!("{} m/s (rad/s)", c.max_velocity)
            } else {
                "off".into()
            },
        ),
        (
            "energy-monitor",
            if c.energy_monitor { "on" } else { "off" }.into(),
        ),
        ("energy-limit", format!("{} J", c.energy_limit)),
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
        (
            "safe-damping",
            format!("{} N·s/m (N·m·s/rad)", c.safe_damping),
        ),
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
