//! What a message is, as values: each message's name ([`HostMsg::name`], [`DeviceMsg::name`]),
//! the [`Request`] a device acknowledges a host message with ([`HostMsg::ack_kind`]), and the
//! classes of [`ErrorCode`] a host acts on ([`ErrorCode::is_framing`],
//! [`ErrorCode::is_transient`]). A host decides by these, never by a message's text or its
//! `Debug` output.
//!
//! Invariant: a name is the variant's identifier, so it stays stable with the wire format.

use crate::msg::{DeviceMsg, ErrorCode, HostMsg, Request};

impl HostMsg {
    /// The message's name (its variant), for errors and logs.
    #[must_use]
    pub fn name(&self) -> &'static str {
        match self {
            Self::Hello { .. } => "Hello",
            Self::GetConfig => "GetConfig",
            Self::SetConfig(_) => "SetConfig",
            Self::SaveConfig => "SaveConfig",
            Self::LoadDefaults => "LoadDefaults",
            Self::StreamStart { .. } => "StreamStart",
            Self::StreamStop => "StreamStop",
            Self::Release { .. } => "Release",
            Self::Excite { .. } => "Excite",
            Self::TableChunk { .. } => "TableChunk",
            Self::Heartbeat => "Heartbeat",
            Self::GetFaults => "GetFaults",
            Self::ClearFaults => "ClearFaults",
            Self::Stop => "Stop",
            Self::Shutdown { .. } => "Shutdown",
            Self::Impact { .. } => "Impact",
            Self::PrepareTest { .. } => "PrepareTest",
            Self::SetProfile(_) => "SetProfile",
            Self::GetProfile => "GetProfile",
        }
    }

    /// The [`Request`] a device's `Ack` to this message carries; `None` for the messages
    /// answered otherwise (`Hello`, `GetConfig`, `LoadDefaults`, `GetFaults`, `GetProfile`).
    #[must_use]
    pub fn ack_kind(&self) -> Option<Request> {
        Some(match self {
            Self::SetConfig(_) => Request::SetConfig,
            Self::SaveConfig => Request::SaveConfig,
            Self::StreamStart { .. } => Request::StreamStart,
            Self::StreamStop => Request::StreamStop,
            Self::Release { .. } => Request::Release,
            Self::Excite { .. } => Request::Excite,
            Self::TableChunk { .. } => Request::TableChunk,
            Self::Heartbeat => Request::Heartbeat,
            Self::ClearFaults => Request::ClearFaults,
            Self::Stop => Request::Stop,
            Self::Shutdown { .. } => Request::Shutdown,
            Self::Impact { .. } => Request::Impact,
            Self::PrepareTest { .. } => Request::PrepareTest,
            Self::SetProfile(_) => Request::SetProfile,
            Self::Hello { .. }
            | Self::GetConfig
            | Self::LoadDefaults
            | Self::GetFaults
            | Self::GetProfile => return None,
        })
    }
}

impl DeviceMsg {
    /// The message's name (its variant), for errors and logs.
    #[must_use]
    pub fn name(&self) -> &'static str {
        match self {
            Self::HelloReply(_) => "HelloReply",
            Self::Config(_) => "Config",
            Self::Ack(_) => "Ack",
            Self::Telemetry(_) => "Telemetry",
            Self::Faults(_) => "Faults",
            Self::ExperimentDone { .. } => "ExperimentDone",
            Self::Error { .. } => "Error",
            Self::Profile(_) => "Profile",
        }
    }
}

impl ErrorCode {
    /// A code a device gives to a frame that did not decode, not to a refused request (it may
    /// answer bad bytes from elsewhere on the link).
    #[must_use]
    pub fn is_framing(self) -> bool {
        matches!(
            self,
            Self::Oversize | Self::Crc | Self::Cobs | Self::UnknownTag | Self::Deserialize
        )
    }

    /// A refusal that passes by itself: the same request may be repeated unchanged.
    #[must_use]
    pub fn is_transient(self) -> bool {
        self == Self::QueueFull
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_the_variants_and_only_the_queue_full_refusal_is_transient() {
        assert_eq!(HostMsg::ClearFaults.name(), "ClearFaults");
        assert_eq!(
            HostMsg::Hello {
                protocol_version: 4
            }
            .name(),
            "Hello"
        );
        assert_eq!(DeviceMsg::Ack(Request::Stop).name(), "Ack");
        assert_eq!(HostMsg::Stop.ack_kind(), Some(Request::Stop));
        assert_eq!(HostMsg::GetFaults.ack_kind(), None);
        assert!(ErrorCode::QueueFull.is_transient());
        assert!(!ErrorCode::Busy.is_transient());
        assert!(ErrorCode::Crc.is_framing() && !ErrorCode::QueueFull.is_framing());
    }
}
