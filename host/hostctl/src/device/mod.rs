//! Talking to a device: the protocol client, transports, virtual device and QEMU launcher live
//! in `stiffwall-client` (re-exported here); this module adds the command line's side: the
//! `--port/--device/--plant/--qemu` options ([`connect`]) and the `--flag` spelling of refused
//! fields in messages ([`client`]).

pub mod client;
pub mod connect;
pub use stiffwall_client::{qemu, transport, virtual_device};
