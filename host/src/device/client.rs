//! The protocol client of `stiffwall-client`, re-exported, with device errors rendered in the
//! command line's terms: a refused field is named by its `--flag`
//! ([`crate::config_flags::flag_name`]).

pub use stiffwall_client::client::*;
use stiffwall_proto::{ErrorCode, ErrorDetail};

/// Renders a device error as a sentence naming the field by its `--flag` and its range.
#[must_use]
pub fn describe_error(code: ErrorCode, detail: &ErrorDetail) -> String {
    describe_error_named(code, detail, crate::config_flags::flag_name)
}
