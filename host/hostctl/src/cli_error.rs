//! Errors in the command line's words: the chain of an error as `{:#}` prints it, except that
//! the device client's errors ([`ClientError`], which name protocol fields) are spelled with
//! this command line's flags: a refused field by its `--flag`
//! ([`crate::config_flags::flag_name`]), a plant file as `--plant FILE`.

use stiffwall_client::{describe_error_named, ClientError, SessionError};

/// An error whose chain [`message`] renders: an `anyhow::Error` or a [`ClientError`].
pub trait ErrorChain {
    /// The error at the head of the chain.
    fn head(&self) -> &(dyn std::error::Error + 'static);
}

impl ErrorChain for anyhow::Error {
    fn head(&self) -> &(dyn std::error::Error + 'static) {
        &**self
    }
}

impl ErrorChain for ClientError {
    fn head(&self) -> &(dyn std::error::Error + 'static) {
        self
    }
}

impl<T: ErrorChain + ?Sized> ErrorChain for &T {
    fn head(&self) -> &(dyn std::error::Error + 'static) {
        (**self).head()
    }
}

/// `e`'s chain joined by `": "` (as `{e:#}`), client errors spelled with `--flag`s.
#[must_use]
pub fn message(e: &impl ErrorChain) -> String {
    std::iter::successors(Some(e.head()), |c| c.source())
        .map(|cause| {
            if let Some(c) = cause.downcast_ref::<ClientError>() {
                client_message(c)
            } else if let Some(s) = cause.downcast_ref::<SessionError>() {
                session_message(s)
            } else {
                cause.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join(": ")
}

/// One session error (not its sources): plan numbers named by their `--flag`.
#[must_use]
pub fn session_message(e: &SessionError) -> String {
    match e {
        SessionError::OutOfRange { name, range, got } => {
            format!("--{name} must be {range} (got {got})")
        }
        SessionError::ReleaseNeedsEveryTick => {
            "--release needs --decimation 1 (experiments stream every tick)".into()
        }
        SessionError::Client(c) => client_message(c),
        e => e.to_string(),
    }
}

/// One client error (not its sources), with the command line's spelling of refused fields and
/// plant files.
#[must_use]
pub fn client_message(e: &ClientError) -> String {
    match e {
        ClientError::Refused {
            request,
            code,
            detail,
        } => format!(
            "{request} refused: {}",
            describe_error_named(*code, detail, crate::config_flags::flag_name)
        ),
        ClientError::Plant {
            path: Some(p),
            message,
        } => format!("--plant {}: {message}", p.display()),
        e => e.to_string(),
    }
}
