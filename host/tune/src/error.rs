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
    /// The tune failed and restoring the previous config failed too.
    #[error("{error}; restoring the previous config failed as well: {restore}")]
    NotRestored {
        /// Why the tune failed.
        error: Box<TuneError>,
        /// Why the restore failed.
        restore: ClientError,
    },
}

impl TuneError {
    /// Classifies an error of the procedure's steps (which carry context as `anyhow`): a
    /// cancel when `cancelled`, a device error when the root cause is one, else the message.
    pub(crate) fn from_step(e: anyhow::Error, cancelled: bool) -> Self {
        if cancelled {
            return Self::Cancelled;
        }
        let during = format!("{e:#}");
        match e.downcast::<ClientError>() {
            Ok(ClientError::Cancelled) => Self::Cancelled,
            Ok(source) => Self::Device { during, source },
            Err(e) => match e.downcast::<SettingsError>() {
                Ok(s) => Self::Settings(s),
                Err(_) => Self::Procedure(during),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use anyhow::Context as _;

    #[test]
    fn a_step_error_is_classified_by_its_root_cause() {
        let e = Err::<(), _>(ClientError::Framing("too long".into()))
            .context("restoring")
            .unwrap_err();
        match TuneError::from_step(e, false) {
            TuneError::Device { during, .. } => assert_eq!(during, "restoring: framing: too long"),
            other => panic!("{other:?}"),
        }
        let e = anyhow::anyhow!("no stiffness passed");
        assert!(
            matches!(TuneError::from_step(e, false), TuneError::Procedure(m) if m == "no stiffness passed")
        );
        let e = anyhow::Error::new(ClientError::Cancelled);
        assert!(matches!(
            TuneError::from_step(e, false),
            TuneError::Cancelled
        ));
        let e = anyhow::anyhow!("anything");
        assert!(matches!(
            TuneError::from_step(e, true),
            TuneError::Cancelled
        ));
    }
}
