//! What can go wrong in a tune, as typed errors (a leaf module): a setting out of range
//! ([`SettingsError`], naming the field of [`crate::settings::Settings`] and its range), a
//! cancel, the device failing ([`stiffwall_client::ClientError`]), or the procedure finding no
//! wall it can verify; and whether the previous config could be restored afterwards.
//!
//! Field names are the Rust field names of `Settings` (`margin`, `max_velocity`, …); a front
//! end that spells them otherwise (a command line's `--max-velocity`, a page's label) renders
//! [`SettingsError`] itself from its fields.

use stiffwall_client::ClientError;

/// A tune setting out of range.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{field} must be {range} (got {got})")]
pub struct SettingsError {
    /// The field of [`crate::settings::Settings`].
    pub field: &'static str,
    /// Its allowed range in words, with units (e.g. `"in (0, 1]"`).
    pub range: String,
    /// The value given.
    pub got: String,
}

/// No stiffness passed a search or a verification set under the tune's criterion (the message
/// says where it looked and what failed). Under the rest criterion, `tune` then looks for the
/// wall with the least chatter instead (see `procedure`).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct NoWallPassed(pub String);

/// Why a tune did not set a wall. Whatever the error, the device was left with the config it
/// had before, unless [`TuneError::NotRestored`] says otherwise.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TuneError {
    /// A setting out of range (checked before any test, or against the device's limits).
    #[error(transparent)]
    Settings(#[from] SettingsError),
    /// The caller's [`stiffwall_client::Cancel`] token was cancelled.
    #[error("cancelled")]
    Cancelled,
    /// The device failed or refused (`during`: the step, with the error's context, in words).
    #[error("{during}")]
    Device {
        /// The step and the device's error, in words.
        during: String,
        /// The device's error.
        #[source]
        source: ClientError,
    },
    /// The procedure could not complete: no stiffness passed, identification failed, … (the
    /// message names the step and what to try).
    #[error("{0}")]
    Procedure(String),
    /// The tune found a wall but the final check failed (the device not at rest, a fault
    /// latched, or not back where it started): nothing was saved, the previous config is back.
    #[error("the tune found a wall but {left}")]
    Left {
        /// The check.
        left: Box<crate::left::DeviceLeft>,
    },
    /// The tune failed and restoring the previous config failed too.
    #[error("{error}; restoring the previous config failed as well: {restore}")]
    NotRestored {
        /// Why the tune failed.
        error: Box<TuneError>,
        /// Why the restore failed.
        restore: ClientError,
    },
}

/// The error of one step of the procedure (identification, a wall test, the search, a
/// prediction): what the public step functions return, and what [`TuneError`] is made of.
/// [`StepError::Context`] says what was being done when an inner error happened; the message
/// is the whole chain, `context: inner` (as the procedure prints it).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum StepError {
    /// The device failed, refused, or the client's cancel token was cancelled (the message is
    /// the client's error with its causes, `error: cause: …`).
    #[error("{}", chain(.0))]
    Device(ClientError),
    /// A setting out of range.
    #[error(transparent)]
    Settings(#[from] SettingsError),
    /// Physical parameters outside the model's domain (a prediction).
    #[error(transparent)]
    Params(#[from] stiffwall_core::params::ParamError),
    /// No stiffness passed a search or a verification set.
    #[error(transparent)]
    NoWallPassed(#[from] NoWallPassed),
    /// The supervisor latched faults (`latched`, the fault bits) during an identification
    /// chirp.
    #[error(
        "the supervisor latched faults {} during the excitation",
        super::left::fault_names(*latched).join(", ")
    )]
    ExcitationTripped {
        /// The latched fault bits.
        latched: u32,
    },
    /// The device did not come to rest within `waited_s` seconds of host time.
    #[error("the device did not come to rest within {waited_s:.0} s")]
    NotAtRest {
        /// The wait, s.
        waited_s: f64,
    },
    /// The step could not complete (the message says why: a singular fit, lost telemetry, …).
    #[error("{0}")]
    Failed(String),
    /// `inner` happened while doing `context`.
    #[error("{context}: {inner}")]
    Context {
        /// What was being done, in words.
        context: String,
        /// What went wrong.
        inner: Box<StepError>,
    },
}

impl StepError {
    /// The innermost error, under every [`StepError::Context`].
    #[must_use]
    pub fn root(&self) -> &StepError {
        match self {
            Self::Context { inner, .. } => inner.root(),
            other => other,
        }
    }

    /// Whether the supervisor latched faults somewhere in this error's chain; their bits.
    #[must_use]
    pub fn tripped(&self) -> Option<u32> {
        match self {
            Self::ExcitationTripped { latched } => Some(*latched),
            Self::Context { context: _, inner } => inner.tripped(),
            _ => None,
        }
    }

    /// The innermost error, owned (the contexts dropped).
    fn into_root(self) -> StepError {
        match self {
            Self::Context { inner, .. } => inner.into_root(),
            other => other,
        }
    }
}

impl From<ClientError> for StepError {
    fn from(e: ClientError) -> Self {
        Self::Device(e)
    }
}

/// `e` and its causes, `error: cause: …`.
fn chain(e: &ClientError) -> String {
    let mut s = e.to_string();
    let mut cause = std::error::Error::source(e);
    while let Some(c) = cause {
        s.push_str(": ");
        s.push_str(&c.to_string());
        cause = c.source();
    }
    s
}

impl From<std::num::TryFromIntError> for StepError {
    fn from(e: std::num::TryFromIntError) -> Self {
        Self::Failed(e.to_string())
    }
}

/// A step's result.
pub(crate) type Result<T, E = StepError> = std::result::Result<T, E>;

/// Adds what was being done to a step's error.
pub(crate) trait Context<T> {
    /// `context: error` on error.
    fn context(self, context: impl Into<String>) -> Result<T>;
}

impl<T, E: Into<StepError>> Context<T> for std::result::Result<T, E> {
    fn context(self, context: impl Into<String>) -> Result<T> {
        self.map_err(|e| StepError::Context {
            context: context.into(),
            inner: Box::new(e.into()),
        })
    }
}

/// Returns early with [`StepError::Failed`] and a formatted message.
macro_rules! bail {
    ($($arg:tt)*) => {
        return Err($crate::error::StepError::Failed(format!($($arg)*)))
    };
}
pub(crate) use bail;

impl TuneError {
    /// Classifies an error of the procedure's steps: a cancel when `cancelled`, a device
    /// error when the root cause is one, else the message.
    pub(crate) fn from_step(e: StepError, cancelled: bool) -> Self {
        if cancelled {
            return Self::Cancelled;
        }
        let during = e.to_string();
        match e.into_root() {
            StepError::Device(ClientError::Cancelled) => Self::Cancelled,
            StepError::Device(source) => Self::Device { during, source },
            StepError::Settings(s) => Self::Settings(s),
            _ => Self::Procedure(during),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_step_error_is_classified_by_its_root_cause() {
        let e = Err::<(), _>(ClientError::Framing("too long".into()))
            .context("restoring")
            .unwrap_err();
        match TuneError::from_step(e, false) {
            TuneError::Device { during, .. } => assert_eq!(during, "restoring: framing: too long"),
            other => panic!("{other:?}"),
        }
        let e = StepError::Failed("no stiffness passed".into());
        assert!(
            matches!(TuneError::from_step(e, false), TuneError::Procedure(m) if m == "no stiffness passed")
        );
        let e = StepError::Device(ClientError::Cancelled);
        assert!(matches!(
            TuneError::from_step(e, false),
            TuneError::Cancelled
        ));
        let e = StepError::Failed("anything".into());
        assert!(matches!(
            TuneError::from_step(e, true),
            TuneError::Cancelled
        ));
    }
}
