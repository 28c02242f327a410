//! Talking to a device: transports (serial port, virtual device over a pty, QEMU over a pty)
//! and the protocol client.

pub mod client;
pub mod connect;
pub mod qemu;
pub mod transport;
pub mod virtual_device;
