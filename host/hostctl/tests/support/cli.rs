//! Shared by the end-to-end tests that run the real `hostctl` binary: run it, require success
//! (stdout) or a clean refusal (exit 2, no panic; stderr), and parse its JSON.

#![allow(dead_code)] // each test crate that includes this module uses part of it

use std::process::{Command, Output};

/// Runs `hostctl ARGS` to completion.
pub fn hostctl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hostctl"))
        .args(args)
        .output()
        .expect("run hostctl")
}

/// Runs a command that must succeed; returns stdout.
pub fn ok(args: &[&str]) -> String {
    let o = hostctl(args);
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    );
    assert!(o.status.success(), "hostctl {args:?} failed:\n{out}\n{err}");
    out
}

/// Runs a command that must fail cleanly (exit 2, no panic); returns stderr.
pub fn fails(args: &[&str]) -> String {
    let o = hostctl(args);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(
        o.status.code(),
        Some(2),
        "hostctl {args:?}: {}\n{err}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert!(
        !err.contains("panicked"),
        "hostctl {args:?} panicked:\n{err}"
    );
    err
}

/// `text` as JSON, or a panic naming the text.
pub fn json(text: &str) -> serde_json::Value {
    serde_json::from_str(text).unwrap_or_else(|e| panic!("{e}: {text}"))
}
