//! Talking to a device: transports (serial port, virtual device over a pty, QEMU over a pty).

pub mod qemu;
pub mod transport;
