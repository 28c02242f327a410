//! Starts the board emulator (`stiffwall-board-emu`, host/board-emu: the Nucleo-F446RE image on
//! an emulated STM32F446 coupled to the simulated plant) as a separate process and finds the
//! pseudo-terminal it serves the emulated USART2 on, the way [`crate::qemu`] boots QEMU.
//!
//! The emulator is GPL-2.0-or-later (it links unicorn); this crate never links it, it only runs
//! its binary. Where things are found: the emulator binary from `$STIFFWALL_BOARD_EMU`, else
//! `host/board-emu/target/release/stiffwall-board-emu` under the current directory or the
//! repository this binary was built from; the image from `$STIFFWALL_NUCLEO_ELF`, else the copy
//! `cargo xtask board-emu` keeps per output (`target/board-emu/nucleo-f446re-{dac,pwm}.elf`), or
//! per output and device where a device has its own rig (`…-dac-phantom-1.0.elf`).
//! Invariants: the process is killed when the handle drops, and it exits by itself when its
//! stdin (held by this handle) closes, so no emulator outlives the host.

use crate::error::{ClientError, Result};
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::time::{Duration, Instant};

/// The force outputs the Nucleo image is built for.
pub const OUTPUTS: &[&str] = &["dac", "pwm"];

/// What to run.
#[derive(Debug, Clone, PartialEq)]
pub struct Spec {
    /// `dac` or `pwm` (None: `dac`).
    pub output: Option<String>,
    /// The plant's preset name (`--device`; None with `plant_file`: `maxon-re35`).
    pub device: Option<String>,
    /// The plant's scene file (`--plant`), instead of a preset.
    pub plant_file: Option<PathBuf>,
    /// Let emulated time run ahead of the wall clock while the host keeps up.
    pub pace: crate::pace::Pace,
}

/// A running emulator; killed when dropped.
#[derive(Debug)]
pub struct BoardEmulator {
    child: Child,
    _stdin: Option<ChildStdin>,
    /// Path of the pseudo-terminal connected to the emulated USART2.
    pub pty: String,
}

impl Drop for BoardEmulator {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl BoardEmulator {
    /// Ends the run the way a host that goes away does: closes the emulator's stdin, then
    /// waits up to `timeout` for it to exit by itself and returns its status (failure when the
    /// run stopped on an unmodelled register or another emulator error).
    pub fn close(mut self, timeout: Duration) -> Result<std::process::ExitStatus> {
        drop(self._stdin.take());
        let deadline = Instant::now() + timeout;
        loop {
            match self.child.try_wait() {
                Ok(Some(status)) => return Ok(status),
                Ok(None) if Instant::now() > deadline => {
                    return Err(err(format!(
                        "the board emulator did not exit within {} s of its stdin closing",
                        timeout.as_secs()
                    )))
                }
                Ok(None) => std::thread::sleep(Duration::from_millis(20)),
                Err(e) => return Err(err(format!("waiting for the board emulator: {e}"))),
            }
        }
    }
}

fn repo_paths(rel: &str) -> Vec<PathBuf> {
    vec![
        PathBuf::from(rel),
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../..")
            .join(rel),
    ]
}

fn err(msg: String) -> ClientError {
    ClientError::Qemu(msg)
}

/// Finds the emulator binary.
pub fn find_emulator() -> Result<PathBuf> {
    if let Some(p) = std::env::var_os("STIFFWALL_BOARD_EMU") {
        let p = PathBuf::from(p);
        return if p.is_file() {
            Ok(p)
        } else {
            Err(err(format!(
                "STIFFWALL_BOARD_EMU={} does not exist",
                p.display()
            )))
        };
    }
    repo_paths("host/board-emu/target/release/stiffwall-board-emu")
        .into_iter()
        .find(|p| p.is_file())
        .ok_or_else(|| {
            err(
                "the board emulator is not built: run `cargo xtask board-emu --build` \
                 (or set STIFFWALL_BOARD_EMU)"
                    .into(),
            )
        })
}

/// Finds the Nucleo image for `output` (`dac` or `pwm`) and, when a preset is named, the image
/// built with that device's rig if there is one (`nucleo-f446re-{output}-{device}.elf`, e.g.
/// the `rig-phantom` build for `phantom-1.0`); otherwise the default image (whose rig the
/// emulator checks against the plant).
pub fn find_image(output: &str, device: Option<&str>) -> Result<PathBuf> {
    if !OUTPUTS.contains(&output) {
        return Err(err(format!(
            "--features {output}: allowed dac or pwm (the Nucleo image's force output)"
        )));
    }
    if let Some(p) = std::env::var_os("STIFFWALL_NUCLEO_ELF") {
        let p = PathBuf::from(p);
        return if p.is_file() {
            Ok(p)
        } else {
            Err(err(format!(
                "STIFFWALL_NUCLEO_ELF={} does not exist",
                p.display()
            )))
        };
    }
    let own = device.map(|d| format!("target/board-emu/nucleo-f446re-{output}-{d}.elf"));
    own.iter()
        .flat_map(|rel| repo_paths(rel))
        .chain(repo_paths(&format!(
            "target/board-emu/nucleo-f446re-{output}.elf"
        )))
        .find(|p| p.is_file())
        .ok_or_else(|| {
            err(format!(
                "the nucleo-f446re {output} image is not built: run `cargo xtask board-emu \
                 --build` (or set STIFFWALL_NUCLEO_ELF)"
            ))
        })
}

/// Starts the emulator for `spec` and waits (up to 20 s) for its pty.
pub fn start(spec: &Spec) -> Result<BoardEmulator> {
    let exe = find_emulator()?;
    let output = spec.output.as_deref().unwrap_or("dac");
    let image = find_image(output, spec.device.as_deref())?;
    let mut cmd = Command::new(&exe);
    cmd.arg("--elf")
        .arg(&image)
        .args(["--output", output, "--pty"]);
    if spec.pace.is_fast() {
        cmd.arg("--fast");
    }
    match (&spec.plant_file, &spec.device) {
        (Some(path), _) => cmd.arg("--plant").arg(path),
        (None, Some(name)) => cmd.args(["--device", name]),
        (None, None) => &mut cmd,
    };
    let mut child = cmd
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .map_err(|e| err(format!("cannot start {}: {e}", exe.display())))?;
    let stdin = child.stdin.take();
    let stdout = child
        .stdout
        .take()
        .ok_or_else(|| err("the board emulator's stdout".into()))?;
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout)
            .lines()
            .map_while(std::result::Result::ok)
        {
            if let Some(path) = line.strip_prefix("pty: ") {
                let _ = tx.send(path.to_string());
            }
        }
    });
    let start = Instant::now();
    loop {
        if let Ok(pty) = rx.recv_timeout(Duration::from_millis(50)) {
            return Ok(BoardEmulator {
                child,
                _stdin: stdin,
                pty,
            });
        }
        if let Ok(Some(status)) = child.try_wait() {
            return Err(err(format!(
                "the board emulator exited before creating its pty ({status}); its error is above"
            )));
        }
        if start.elapsed() > Duration::from_secs(20) {
            let _ = child.kill();
            return Err(err(
                "the board emulator did not report its pty within 20 s".into()
            ));
        }
    }
}
