//! Standard output of every `hostctl` command: one writer for tables and JSON reports.
//!
//! Units: none (text). Invariants: every report ends with exactly one newline (added when the
//! text lacks it); JSON is pretty-printed; a closed pipe (`hostctl info | head`) is not an
//! error, any other write failure is.

use serde::Serialize;

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
