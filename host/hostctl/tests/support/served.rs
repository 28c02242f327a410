//! `hostctl virtual` serving its pty for several hostctl runs (one device, its config, profile
//! and latched faults outliving each run), stopped with SIGINT (its Ctrl-C) when dropped.

#![allow(dead_code)] // each test crate that includes this module uses part of it

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// A served virtual device.
pub struct Served {
    child: Child,
    /// Its pseudo-terminal.
    pub pty: String,
}

impl Served {
    /// `hostctl virtual` (paced, the default preset).
    pub fn start() -> Self {
        Self::with(&[])
    }

    /// `hostctl virtual EXTRA…` (e.g. `--device maxon-re35 --fast`).
    pub fn with(extra: &[&str]) -> Self {
        let mut child = Command::new(env!("CARGO_BIN_EXE_hostctl"))
            .arg("virtual")
            .args(extra)
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut line)
            .unwrap();
        let pty = line.trim().strip_prefix("pty: ").expect(&line).to_string();
        Self { child, pty }
    }

    /// `args` with `--port PTY` appended.
    pub fn args<'a>(&'a self, args: &[&'a str]) -> Vec<&'a str> {
        let mut v = args.to_vec();
        v.extend(["--port", self.pty.as_str()]);
        v
    }
}

impl Drop for Served {
    fn drop(&mut self) {
        let pid = self.child.id().to_string();
        let _ = Command::new("kill").args(["-INT", &pid]).status();
        let t0 = Instant::now();
        while t0.elapsed() < Duration::from_secs(10) {
            if let Ok(Some(_)) = self.child.try_wait() {
                return;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
