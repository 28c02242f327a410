//! `stiffwall-client`: the host side of the stiffwall protocol as a library, with no
//! command-line code. [`client`] is the protocol client (handshake with version check,
//! request/answer with timeouts, telemetry with sequence-gap accounting, experiments);
//! [`transport`] opens serial ports and pseudo-terminals; [`virtual_device`] runs the firmware
//! core against a simulated plant in-process; [`qemu`] boots the board image; [`session`] is
//! the telemetry pump and lossless recorder; [`recording`] the CSV recording format.
//!
//! Units: SI at the API, device integers on the wire (as documented per module).
//! Invariants: the client never names command-line flags; refused fields are named by the
//! protocol ([`stiffwall_proto::ConfigField::name`]) unless a front end supplies its spelling
//! ([`client::Client::set_field_label`]). This crate installs no signal handler: a front end
//! sets [`session::INTERRUPTED`].

pub mod client;
pub mod qemu;
pub mod recording;
pub mod session;
pub mod transport;
pub mod virtual_device;
