//! The protocol client of `stiffwall-client`, re-exported. Its errors name refused fields by
//! their protocol names; the command line spells them as `--flag`s when it prints them
//! ([`crate::cli_error`]).

pub use stiffwall_client::client::*;
pub use stiffwall_client::error::ClientError;
