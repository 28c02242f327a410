//! Finds (and, when it may, installs) what the cross builds and QEMU runs need.
//!
//! Order of preference (docs/toolchain.md):
//! 1. rustup's toolchain with the `thumbv7em-none-eabihf` target (`rustup target add`), linked by
//!    `rust-lld` (the thumb targets' default);
//! 2. Debian's `rustc-web`/`cargo-web`/`rust-web-src` building `core` from source
//!    (`-Z build-std=core`), linked by `arm-none-eabi-ld`.
//!
//! Missing Debian packages are installed with `apt-get` when running as root on Debian;
//! elsewhere the error names the one command the user needs.

use anyhow::{bail, Result};
use std::path::Path;
use std::process::{Command, Stdio};

/// The Cortex-M4F target triple.
pub const TARGET: &str = "thumbv7em-none-eabihf";

/// How board crates get built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cross {
    /// rustup toolchain with the target's prebuilt `core`.
    Rustup,
    /// Debian's rustc building `core` from source.
    DebianBuildStd,
}

fn quiet_ok(cmd: &mut Command) -> bool {
    cmd.stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .map(|s| s.success())
        .unwrap_or(false)
}

fn output(cmd: &mut Command) -> Option<String> {
    let out = cmd.stderr(Stdio::null()).output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).into_owned())
}

fn is_root() -> bool {
    output(Command::new("id").arg("-u")).is_some_and(|s| s.trim() == "0")
}

fn is_debian() -> bool {
    Path::new("/etc/debian_version").exists()
}

/// Installs Debian packages when allowed, otherwise fails naming the command to run.
pub fn apt_install(packages: &[&str], why: &str) -> Result<()> {
    let line = format!("apt-get install -y {}", packages.join(" "));
    if !(is_root() && is_debian()) {
        bail!("{why} is missing; install it with: sudo {line}");
    }
    eprintln!("xtask: installing {why}: {line}");
    let install = |update: bool| -> bool {
        if update {
            let _ = Command::new("apt-get").args(["update", "-q"]).status();
        }
        Command::new("apt-get")
            .args(["install", "-y", "-q", "--no-install-recommends"])
            .args(packages)
            .env("DEBIAN_FRONTEND", "noninteractive")
            .status()
            .map(|s| s.success())
            .unwrap_or(false)
    };
    if install(false) || install(true) {
        Ok(())
    } else {
        bail!("`{line}` failed; {why} is needed")
    }
}

/// Makes sure the thumb target can be built, preferring rustup.
pub fn ensure_cross() -> Result<Cross> {
    let installed = output(Command::new("rustup").args(["target", "list", "--installed"]));
    if installed
        .as_deref()
        .is_some_and(|s| s.lines().any(|l| l.trim() == TARGET))
    {
        return Ok(Cross::Rustup);
    }
    if installed.is_some() {
        eprintln!("xtask: rustup target add {TARGET}");
        if quiet_ok(Command::new("rustup").args(["target", "add", TARGET])) {
            return Ok(Cross::Rustup);
        }
        eprintln!("xtask: rustup could not add {TARGET}; falling back to Debian's rustc-web");
    }
    let have_debian = Path::new("/usr/bin/rustc").exists()
        && Path::new("/usr/bin/cargo").exists()
        && Path::new("/usr/lib/rustlib/src").exists()
        && which("arm-none-eabi-ld");
    if !have_debian {
        apt_install(
            &[
                "rustc-web",
                "cargo-web",
                "rust-web-src",
                "binutils-arm-none-eabi",
            ],
            "the fallback Cortex-M toolchain",
        )?;
    }
    Ok(Cross::DebianBuildStd)
}

/// True when `prog` is on PATH.
pub fn which(prog: &str) -> bool {
    std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|dir| dir.join(prog).is_file()))
}

/// Makes sure `qemu-system-arm` is installed.
pub fn ensure_qemu() -> Result<()> {
    if which("qemu-system-arm") {
        return Ok(());
    }
    apt_install(&["qemu-system-arm"], "QEMU (qemu-system-arm)")?;
    if !which("qemu-system-arm") {
        bail!("qemu-system-arm still not on PATH after installing it");
    }
    Ok(())
}

/// A `cargo build` command for a board crate directory, for the chosen toolchain.
pub fn board_build(cross: Cross, board_dir: &Path, features: &[&str]) -> Result<Command> {
    let mut cmd;
    match cross {
        Cross::Rustup => {
            cmd = Command::new("cargo");
            // The host workspace's `cargo xtask` exports these; they must not leak into the
            // board build, which has its own workspace and target.
            cmd.env_remove("CARGO_TARGET_DIR");
            cmd.args(["build", "--release"]);
        }
        Cross::DebianBuildStd => {
            cmd = Command::new("/usr/bin/cargo");
            cmd.env("RUSTC", "/usr/bin/rustc")
                .env("RUSTC_BOOTSTRAP", "1")
                .env(
                    "RUSTFLAGS",
                    "-C linker=arm-none-eabi-ld -C link-arg=-Tlink.x",
                )
                .args(["build", "--release", "-Z", "build-std=core"]);
        }
    }
    cmd.args(["--target", TARGET]).current_dir(board_dir);
    if !features.is_empty() {
        cmd.args(["--features", &features.join(",")]);
    }
    if !board_dir.join("Cargo.toml").exists() {
        bail!("no board crate at {}", board_dir.display());
    }
    Ok(cmd)
}
