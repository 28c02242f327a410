//! Talking to a device: the protocol client, transports, virtual device and QEMU launcher live
//! in `stiffwall-client`; this module adds the command line's side: the
//! `--port/--device/--plant/--qemu` options ([`connect`]) (the `--flag` spelling of refused
//! fields in messages is [`crate::cli_error`]'s).

pub mod connect;
