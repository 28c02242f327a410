//! Why a map spec or file is refused ([`MapFileError`]), this module's `Result`, and the
//! `ensure!` shorthand the checks of the other map-file modules return their errors with.
use std::path::PathBuf;

/// Why a map spec or file is refused; every message names the file (where there is one), the
/// field and what was allowed or expected.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MapFileError {
    /// A spec field outside its allowed range (the message names the field and the range).
    #[error("{0}")]
    Spec(String),
    /// A file whose spec is invalid (the source names the field).
    #[error("{path}: invalid spec")]
    InvalidSpec {
        /// The file.
        path: PathBuf,
        /// What is wrong with the spec.
        #[source]
        source: Box<MapFileError>,
    },
    /// A file whose content contradicts its spec (the message names the file and field).
    #[error("{0}")]
    Content(String),
    /// Files that do not merge into one map (mismatched sweeps, shards twice or missing).
    #[error("{0}")]
    Merge(String),
    /// A file that could not be read.
    #[error("reading {path}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A file whose JSON ends early.
    #[error("{path}: truncated (the JSON ends early: {error}); re-run its shard")]
    Truncated {
        /// The file.
        path: PathBuf,
        /// The parser's error.
        error: serde_json::Error,
    },
    /// A file that is not a map file.
    #[error("{path}: not a map file: {error}")]
    NotAMapFile {
        /// The file.
        path: PathBuf,
        /// The parser's error.
        error: serde_json::Error,
    },
    /// A file that could not be written.
    #[error("writing {path}")]
    Write {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
}

/// `Result` of this module.
pub type Result<T, E = MapFileError> = std::result::Result<T, E>;

/// Returns `Err(MapFileError::$kind(format!(...)))` unless `$cond` holds.
macro_rules! ensure {
    ($kind:ident, $cond:expr, $($fmt:tt)*) => {
        if !$cond {
            return Err(MapFileError::$kind(format!($($fmt)*)));
        }
    };
}
pub(super) use ensure;
