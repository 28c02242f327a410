//! What can go wrong talking to a device, as one typed error ([`ClientError`]): a refusal
//! carries the protocol's field and its range (not a sentence), a hang-up is its own variant
//! (never found by searching an error chain), and so are timeouts, a protocol version
//! mismatch and framing trouble.
//!
//! Messages name refused fields by their protocol name ([`stiffwall_proto::ConfigField::name`]);
//! a front end that spells them otherwise (a command line's `--flag`) renders
//! [`ClientError::Refused`] itself from its fields, e.g. with
//! [`crate::describe::describe_error_named`].

use crate::describe::describe_error;
use std::io;
use std::path::PathBuf;
use std::time::Duration;
use stiffwall_proto::{ErrorCode, ErrorDetail};

/// An error of the device client.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ClientError {
    /// The device refused a request (`request`: its message name, e.g. `"SetConfig"`, or
    /// `"handshake"`). A field out of range is `detail`: [`ErrorDetail::Field`] with the
    /// protocol field and its allowed range.
    #[error("{request} refused: {}", describe_error(*code, detail))]
    Refused {
        /// The refused request.
        request: String,
        /// The device's error code.
        code: ErrorCode,
        /// What the device says about it (field and range, version, text).
        detail: ErrorDetail,
    },
    /// The link went away: the device hung up or closed its end.
    #[error("the device closed the connection (while {op})")]
    HangUp {
        /// What the client was doing (`"reading"`, `"writing"`).
        op: &'static str,
        /// The transport's error.
        #[source]
        source: io::Error,
    },
    /// The transport failed otherwise.
    #[error("{op} the device")]
    Io {
        /// What the client was doing (`"reading from"`, `"writing to"`).
        op: &'static str,
        /// The transport's error.
        #[source]
        source: io::Error,
    },
    /// No answer in time (`request`: the request waited for, when there was one).
    #[error(
        "no answer{} within {} ms{}",
        request.as_ref().map(|r| format!(" to {r}")).unwrap_or_default(),
        waited.as_millis(),
        bad_frames.as_ref().map(|b| format!(" (the device reported bad frames: {b})")).unwrap_or_default()
    )]
    Timeout {
        /// The request whose answer did not come.
        request: Option<String>,
        /// How long the client waited.
        waited: Duration,
        /// The last framing error the device reported meanwhile, in words.
        bad_frames: Option<String>,
    },
    /// The device stopped reading what the client writes.
    #[error("{}", if *link_full {
        format!("the link is full: the device keeps reading bad frames from elsewhere on the line, \
                 and this request could not get in for {} ms", waited.as_millis())
    } else {
        format!("the device stopped reading (no progress writing for {} ms)", waited.as_millis())
    })]
    WriteStalled {
        /// How long the write made no progress.
        waited: Duration,
        /// Whether the device was visibly busy answering bad frames from elsewhere.
        link_full: bool,
    },
    /// An experiment did not end in time.
    #[error("the experiment did not finish within {} s", .0.as_secs())]
    ExperimentTimeout(Duration),
    /// The caller's [`crate::Cancel`] token was cancelled while an experiment ran; the device
    /// was told to stop and ended the test.
    #[error("cancelled")]
    Cancelled,
    /// The device speaks another protocol version.
    #[error(
        "device speaks protocol version {device}, this host speaks {host}; update the {}",
        if device > host { "host" } else { "firmware" }
    )]
    VersionMismatch {
        /// The device's protocol version.
        device: u8,
        /// This client's ([`stiffwall_proto::PROTOCOL_VERSION`]).
        host: u8,
    },
    /// The handshake got no usable answer (the last failure is the source).
    #[error("the device never answered the handshake (wrong port, wrong baud rate, or not running stiffwall firmware?)")]
    NoHandshake(#[source] Box<ClientError>),
    /// A frame could not be encoded (too long for the protocol).
    #[error("framing: {0}")]
    Framing(String),
    /// The device answered with a message that does not answer the request.
    #[error("unexpected answer to {request}: {answer}")]
    Unexpected {
        /// The request.
        request: String,
        /// The answer (debug form).
        answer: String,
    },
    /// A serial port could not be opened (missing, busy, forbidden, bad baud rate).
    #[error("{0}")]
    Port(String),
    /// The virtual device's plant is not usable (`path`: its plant file, if any).
    #[error("{}{message}", path.as_ref().map(|p| format!("plant file {}: ", p.display())).unwrap_or_default())]
    Plant {
        /// The plant file.
        path: Option<PathBuf>,
        /// What is wrong, naming the key and its range.
        message: String,
    },
    /// The QEMU board image could not be found or booted.
    #[error("{0}")]
    Qemu(String),
}

impl ClientError {
    /// Whether this is the link going away (the device hung up or closed its end), as opposed
    /// to a refusal, a timeout or garbage.
    #[must_use]
    pub fn is_hangup(&self) -> bool {
        matches!(self, Self::HangUp { .. })
    }

    /// A transport error while doing `op` (`"reading"` / `"writing"`): a hang-up when the
    /// link went away, else [`ClientError::Io`].
    pub(crate) fn io(op: &'static str, source: io::Error) -> Self {
        if matches!(
            source.kind(),
            io::ErrorKind::BrokenPipe
                | io::ErrorKind::UnexpectedEof
                | io::ErrorKind::ConnectionReset
        ) {
            Self::HangUp { op, source }
        } else {
            let op = if op == "reading" {
                "reading from"
            } else {
                "writing to"
            };
            Self::Io { op, source }
        }
    }
}

/// Result of the device client.
pub type Result<T, E = ClientError> = std::result::Result<T, E>;
