//! Boots the QEMU board image (`firmware/boards/qemu-an386`) with `-serial pty` and finds the
//! pseudo-terminal QEMU created, so hostctl can talk to the real Cortex-M firmware.

use crate::error::{ClientError, Result};
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// A running QEMU; killed when dropped.
#[derive(Debug)]
pub struct Qemu {
    child: Child,
    /// Path of the pseudo-terminal connected to the image's UART0.
    pub pty: String,
    reaped: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

impl Drop for Qemu {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        self.reaped
            .store(true, std::sync::atomic::Ordering::Relaxed);
    }
}

impl Qemu {
    /// Waits up to `timeout` for QEMU to exit by itself (semihosting exit) and returns its status.
    pub fn wait_exit(&mut self, timeout: Duration) -> Result<std::process::ExitStatus> {
        let deadline = Instant::now() + timeout;
        loop {
            if let Some(status) = self.child.try_wait().map_err(qemu_io)? {
                return Ok(status);
            }
            if Instant::now() > deadline {
                return Err(ClientError::Qemu(format!(
                    "QEMU did not exit within {} s",
                    timeout.as_secs()
                )));
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

/// Where `cargo xtask firmware` leaves the QEMU image, relative to the repository root.
pub const DEFAULT_IMAGE: &str =
    "firmware/boards/qemu-an386/target/thumbv7em-none-eabihf/release/stiffwall-qemu-an386";

/// Finds the QEMU image: an explicit path, `$STIFFWALL_QEMU_IMAGE`, or the default build path
/// under the current directory or the repository this binary was built from.
pub fn find_image(explicit: Option<&Path>) -> Result<PathBuf> {
    if let Some(p) = explicit {
        if p.is_file() {
            return Ok(p.to_path_buf());
        }
        return Err(ClientError::Qemu(format!(
            "QEMU image {} does not exist",
            p.display()
        )));
    }
    if let Some(p) = std::env::var_os("STIFFWALL_QEMU_IMAGE") {
        let p = PathBuf::from(p);
        if p.is_file() {
            return Ok(p);
        }
        return Err(ClientError::Qemu(format!(
            "STIFFWALL_QEMU_IMAGE={} does not exist",
            p.display()
        )));
    }
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    for base in [PathBuf::from("."), repo] {
        let p = base.join(DEFAULT_IMAGE);
        if p.is_file() {
            return Ok(p);
        }
    }
    Err(ClientError::Qemu(
        "no QEMU image found; build it with `cargo xtask firmware` or pass --qemu-image PATH"
            .into(),
    ))
}

/// Longest a QEMU instance may live; a watchdog kills it after that even if the host hangs.
pub const TIME_LIMIT: Duration = Duration::from_secs(600);

/// Boots `image` under QEMU (mps2-an386, Cortex-M4F) with UART0 on a new pseudo-terminal.
/// The instance is killed when the returned [`Qemu`] is dropped, or after [`TIME_LIMIT`].
pub fn boot(image: &Path) -> Result<Qemu> {
    let mut child = spawn(image)?;
    // QEMU announces the pty on stdout; the semihosting console shares stdout, so a thread
    // keeps draining it for the life of the process (and forwards the console to stderr).
    // Time limit without `unsafe`: a thread that kills the process by PID unless it has
    // already been reaped (checked through the shared flag set on drop).
    let reaped = watchdog(child.id());
    let stdout = child
        .stdout
        .take()
        .ok_or_else(|| ClientError::Qemu("QEMU stdout".into()))?;
    let rx = drain(stdout);
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        if let Ok(pty) = rx.recv_timeout(Duration::from_millis(50)) {
            return Ok(Qemu { child, pty, reaped });
        }
        if let Some(status) = child.try_wait().map_err(qemu_io)? {
            return Err(ClientError::Qemu(format!(
                "QEMU exited before creating its pty ({status})"
            )));
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            return Err(ClientError::Qemu(
                "QEMU did not report its pty within 10 s".into(),
            ));
        }
    }
}

/// Starts `qemu-system-arm` on `image` with UART0 on `-serial pty` and stdout piped.
fn spawn(image: &Path) -> Result<Child> {
    Command::new("qemu-system-arm")
        .args([
            "-cpu",
            "cortex-m4",
            "-machine",
            "mps2-an386",
            "-display",
            "none",
        ])
        .args([
            "-monitor",
            "none",
            "-semihosting-config",
            "enable=on,target=native",
        ])
        .args(["-serial", "pty", "-kernel"])
        .arg(image)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .map_err(|e| {
            if e.kind() == std::io::ErrorKind::NotFound {
                ClientError::Qemu(
                    "qemu-system-arm is not installed (Debian: apt-get install qemu-system-arm)"
                        .into(),
                )
            } else {
                ClientError::Qemu(format!("cannot start qemu-system-arm: {e}"))
            }
        })
}

/// A thread that kills process `pid` after [`TIME_LIMIT`] unless the returned flag is set
/// (on drop, once the process is reaped) first; polls every 200 ms.
fn watchdog(pid: u32) -> std::sync::Arc<std::sync::atomic::AtomicBool> {
    let reaped = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let reaped2 = std::sync::Arc::clone(&reaped);
    std::thread::spawn(move || {
        let start = Instant::now();
        while start.elapsed() < TIME_LIMIT {
            if reaped2.load(std::sync::atomic::Ordering::Relaxed) {
                return;
            }
            std::thread::sleep(Duration::from_millis(200));
        }
        eprintln!("qemu: killing pid {pid} after {} s", TIME_LIMIT.as_secs());
        let _ = Command::new("kill").args(["-9", &pid.to_string()]).status();
    });
    reaped
}

/// A thread that reads QEMU's `stdout` to its end, forwarding the console to stderr and
/// sending the path of each pty QEMU announces ("... redirected to PATH ...").
fn drain(stdout: std::process::ChildStdout) -> std::sync::mpsc::Receiver<String> {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout)
            .lines()
            .map_while(std::result::Result::ok)
        {
            if !line.contains("redirected to ") {
                eprintln!("qemu: {line}");
            }
            if let Some(rest) = line.split("redirected to ").nth(1) {
                let path = rest.split_whitespace().next().unwrap_or("").to_string();
                let _ = tx.send(path);
            }
        }
    });
    rx
}

fn qemu_io(e: std::io::Error) -> ClientError {
    ClientError::Qemu(format!("waiting for QEMU: {e}"))
}
