//! Byte transports to a device: anything [`Transport`] (Read + Write whose reads time out),
//! such as a real serial port, a pseudo-terminal pair (virtual device), the pseudo-terminal
//! that QEMU's `-serial pty` creates, or an in-memory pair ([`memory_pair`]).
//!
//! The virtual device and QEMU are reached through a `serialport::SerialPort` opened by path,
//! so the code that talks to them is the code that talks to a real board.

use crate::error::{ClientError, Result};
use std::collections::VecDeque;
use std::io::{self, Read, Write};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;

/// A byte link to a device: [`Read`] + [`Write`], where a read with nothing to read waits at
/// most about [`READ_TIMEOUT`] and then fails with [`io::ErrorKind::TimedOut`] or
/// [`io::ErrorKind::WouldBlock`] (`Ok(0)` means the other end closed the link).
pub trait Transport: Read + Write + Send + std::fmt::Debug {
    /// Bytes that can be read now without waiting (0 when unknown).
    fn bytes_to_read(&mut self) -> io::Result<u32> {
        Ok(0)
    }
}

impl Transport for Box<dyn serialport::SerialPort> {
    fn bytes_to_read(&mut self) -> io::Result<u32> {
        serialport::SerialPort::bytes_to_read(self.as_ref()).map_err(io::Error::from)
    }
}

impl Transport for serialport::TTYPort {
    fn bytes_to_read(&mut self) -> io::Result<u32> {
        serialport::SerialPort::bytes_to_read(self).map_err(io::Error::from)
    }
}

impl<T: Transport + ?Sized> Transport for Box<T> {
    fn bytes_to_read(&mut self) -> io::Result<u32> {
        (**self).bytes_to_read()
    }
}

/// One end of an in-memory link ([`memory_pair`]).
#[derive(Debug)]
pub struct MemoryPort {
    rx: Arc<Pipe>,
    tx: Arc<Pipe>,
}

#[derive(Debug, Default)]
struct Pipe {
    state: Mutex<(VecDeque<u8>, bool)>,
    ready: Condvar,
}

/// Two connected in-memory ends: what one writes, the other reads. Reads wait up to
/// [`READ_TIMEOUT`]; when one end is dropped, the other reads `Ok(0)` and writes fail with
/// [`io::ErrorKind::BrokenPipe`].
#[must_use]
pub fn memory_pair() -> (MemoryPort, MemoryPort) {
    let (a, b) = (Arc::new(Pipe::default()), Arc::new(Pipe::default()));
    (
        MemoryPort {
            rx: a.clone(),
            tx: b.clone(),
        },
        MemoryPort { rx: b, tx: a },
    )
}

impl Drop for MemoryPort {
    fn drop(&mut self) {
        for p in [&self.rx, &self.tx] {
            if let Ok(mut s) = p.state.lock() {
                s.1 = true;
            }
            p.ready.notify_all();
        }
    }
}

impl Read for MemoryPort {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let s = self.rx.state.lock().map_err(|_| io::ErrorKind::Other)?;
        let (mut s, _) = self
            .rx
            .ready
            .wait_timeout_while(s, READ_TIMEOUT, |s| s.0.is_empty() && !s.1)
            .map_err(|_| io::ErrorKind::Other)?;
        if s.0.is_empty() {
            return if s.1 {
                Ok(0)
            } else {
                Err(io::ErrorKind::TimedOut.into())
            };
        }
        let n = buf.len().min(s.0.len());
        for (b, x) in buf.iter_mut().zip(s.0.drain(..n)) {
            *b = x;
        }
        Ok(n)
    }
}

impl Write for MemoryPort {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let mut s = self.tx.state.lock().map_err(|_| io::ErrorKind::Other)?;
        if s.1 {
            return Err(io::ErrorKind::BrokenPipe.into());
        }
        s.0.extend(buf);
        self.tx.ready.notify_all();
        Ok(buf.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

impl Transport for MemoryPort {
    fn bytes_to_read(&mut self) -> io::Result<u32> {
        let s = self.rx.state.lock().map_err(|_| io::ErrorKind::Other)?;
        Ok(u32::try_from(s.0.len()).unwrap_or(u32::MAX))
    }
}

/// Default baud rate: the Nucleo's ST-LINK virtual COM port at 921600 baud.
pub const DEFAULT_BAUD: u32 = 921_600;
/// Read timeout of an opened port; the protocol client polls with this granularity.
pub const READ_TIMEOUT: Duration = Duration::from_millis(20);

/// Opens a serial port by path with a clear error for a missing, busy or forbidden port.
pub fn open_port(path: &str, baud: u32) -> Result<Box<dyn serialport::SerialPort>> {
    if baud == 0 || baud > 12_000_000 {
        return Err(ClientError::Port(format!(
            "--baud must be between 1 and 12000000 (got {baud})"
        )));
    }
    if !std::path::Path::new(path).exists() {
        return Err(ClientError::Port(format!(
            "serial port {path} does not exist (is the board plugged in? on Linux it is usually /dev/ttyACM0)"
        )));
    }
    let port = serialport::new(path, baud)
        .timeout(READ_TIMEOUT)
        .open()
        .map_err(|e| match e.kind() {
            serialport::ErrorKind::NoDevice => ClientError::Port(format!(
                "serial port {path} is busy or gone ({e}); is another program using it?"
            )),
            serialport::ErrorKind::Io(std::io::ErrorKind::PermissionDenied) => ClientError::Port(
                format!("no permission to open {path} ({e}); add yourself to the dialout group"),
            ),
            _ => ClientError::Port(format!("cannot open serial port {path}: {e}")),
        })?;
    Ok(port)
}

/// A pseudo-terminal pair for the virtual device: the device side (master), and the host side
/// opened by its path like any serial port, with that path.
pub fn pty_pair() -> Result<(serialport::TTYPort, Box<dyn serialport::SerialPort>, String)> {
    let (master, slave) = serialport::TTYPort::pair().map_err(|e| {
        ClientError::Port(format!(
            "creating a pseudo-terminal for the virtual device: {e}"
        ))
    })?;
    let name = slave
        .name()
        .ok_or_else(|| ClientError::Port("the pseudo-terminal has no name".into()))?;
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
    fn memory_pair_carries_bytes_times_out_and_hangs_up() {
        let (mut a, mut b) = memory_pair();
        a.write_all(&[1, 2, 0, 3]).unwrap();
        assert_eq!(b.bytes_to_read().unwrap(), 4);
        let mut buf = [0u8; 8];
        assert_eq!(b.read(&mut buf).unwrap(), 4);
        assert_eq!(buf[..4], [1, 2, 0, 3]);
        let e = b.read(&mut buf).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::TimedOut);
        drop(a);
        assert_eq!(b.read(&mut buf).unwrap(), 0, "the other end closed");
        let e = b.write(&[1]).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::BrokenPipe);
    }

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
