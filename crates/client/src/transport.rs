//! Byte transports to a device: a real serial port, a pseudo-terminal pair (virtual device), or
//! the pseudo-terminal that QEMU's `-serial pty` creates.
//!
//! Every transport ends up as a `serialport::SerialPort` opened by path, so the host code that
//! talks to the built-in virtual device or to QEMU is the code that talks to a real board.

use anyhow::{anyhow, Context, Result};
use std::time::Duration;

/// Default baud rate: the Nucleo's ST-LINK virtual COM port at 921600 baud.
pub const DEFAULT_BAUD: u32 = 921_600;
/// Read timeout of an opened port; the protocol client polls with this granularity.
pub const READ_TIMEOUT: Duration = Duration::from_millis(20);

/// Opens a serial port by path with a clear error for a missing, busy or forbidden port.
pub fn open_port(path: &str, baud: u32) -> Result<Box<dyn serialport::SerialPort>> {
    if baud == 0 || baud > 12_000_000 {
        return Err(anyhow!(
            "--baud must be between 1 and 12000000 (got {baud})"
        ));
    }
    if !std::path::Path::new(path).exists() {
        return Err(anyhow!(
            "serial port {path} does not exist (is the board plugged in? on Linux it is usually /dev/ttyACM0)"
        ));
    }
    let port = serialport::new(path, baud)
        .timeout(READ_TIMEOUT)
        .open()
        .map_err(|e| match e.kind() {
            serialport::ErrorKind::NoDevice => {
                anyhow!("serial port {path} is busy or gone ({e}); is another program using it?")
            }
            serialport::ErrorKind::Io(std::io::ErrorKind::PermissionDenied) => {
                anyhow!("no permission to open {path} ({e}); add yourself to the dialout group")
            }
            _ => anyhow!("cannot open serial port {path}: {e}"),
        })?;
    Ok(port)
}

/// A pseudo-terminal pair for the virtual device: the device side (master), and the host side
/// opened by its path like any serial port, with that path.
pub fn pty_pair() -> Result<(serialport::TTYPort, Box<dyn serialport::SerialPort>, String)> {
    let (master, slave) =
        serialport::TTYPort::pair().context("creating a pseudo-terminal for the virtual device")?;
    let name = slave
        .name()
        .ok_or_else(|| anyhow!("the pseudo-terminal has no name"))?;
    // Open the host side by path, as a real port would be; `slave` stays open until then so the
    // pty never sees a hang-up.
    let host = open_port(&name, DEFAULT_BAUD)?;
    drop(slave);
    Ok((master, host, name))
}

use serialport::SerialPort as _;

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{Read, Write};

    #[test]
    fn pty_pair_carries_bytes_both_ways() {
        let (mut master, mut host, name) = pty_pair().unwrap();
        assert!(name.starts_with("/dev/"), "{name}");
        host.write_all(&[0x00, 0x01, 0xff, b'\n', 0x7f]).unwrap();
        let mut buf = [0u8; 5];
        master.read_exact(&mut buf).unwrap();
        assert_eq!(
            buf,
            [0x00, 0x01, 0xff, b'\n', 0x7f],
            "raw mode: no byte translated"
        );
        master.write_all(&[0x11, 0x13, 0x00]).unwrap();
        let mut buf = [0u8; 3];
        host.read_exact(&mut buf).unwrap();
        assert_eq!(buf, [0x11, 0x13, 0x00], "XON/XOFF bytes pass through");
    }

    #[test]
    fn missing_port_is_a_clear_error() {
        let e = open_port("/dev/does-not-exist-stiffwall", DEFAULT_BAUD).unwrap_err();
        assert!(e.to_string().contains("does not exist"), "{e}");
        let e = open_port("/dev/null", 0).unwrap_err();
        assert!(e.to_string().contains("--baud"), "{e}");
    }
}
