//! Finds (and, when it may, installs) what the cross builds and QEMU runs need.
//!
//! Order of preference (see docs/toolchain.md):
//! 1. rustup's toolchain with the `thumbv7em-none-eabihf` target (`rustup target add`), linked by
//!    `rust-lld` (the thumb targets' default);
//! 2. Debian's `rustc-web`/`cargo-web`/`rust-web-src` building `core` from source
//!    (`-Z build-std=core`), linked by `arm-none-eabi-ld`.
//!
//! Debian's `chromium` and `chromium-driver` drive the real-browser test of `hostctl ui`;
//! `cmake` and `libclang-dev` build the board emulator's unicorn core (host/board-emu).
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
///
/// Never removes or downgrades anything the machine has: the install runs with `--no-remove`,
/// and what it will install is printed (from `apt-get install -s`) before it does so. A plan
/// that needs a removal fails with the plan in the message instead.
pub fn apt_install(packages: &[&str], why: &str) -> Result<()> {
    let line = format!("apt-get install -y --no-remove {}", packages.join(" "));
    if !(is_root() && is_debian()) {
        bail!("{why} is missing; install it with: sudo {line}");
    }
    let apt = |args: &[&str]| {
        let mut c = Command::new("apt-get");
        c.args(args)
            .args(["-q", "--no-install-recommends", "--no-remove"])
            .args(packages)
            .env("DEBIAN_FRONTEND", "noninteractive");
        c
    };
    let plan = |update: bool| -> Option<String> {
        if update {
            let _ = Command::new("apt-get").args(["update", "-q"]).status();
        }
        output(&mut apt(&["install", "-s"]))
    };
    let Some(plan) = plan(false).or_else(|| plan(true)) else {
        bail!(
            "`{line}` cannot be done without removing or downgrading installed packages \
             (see `apt-get install -s {}`); {why} is needed",
            packages.join(" ")
        );
    };
    let new: Vec<&str> = plan
        .lines()
        .filter_map(|l| l.strip_prefix("Inst "))
        .map(|l| l.split_whitespace().next().unwrap_or(l))
        .collect();
    eprintln!(
        "xtask: installing {why}: {line}\nxtask: this installs {} package(s): {}",
        new.len(),
        new.join(" ")
    );
    if apt(&["install", "-y"])
        .status()
        .map(|s| s.success())
        .unwrap_or(false)
    {
        Ok(())
    } else {
        bail!("`{line}` failed; {why} is needed")
    }
}

/// The installed version of a Debian package, if any.
fn installed_version(package: &str) -> Option<String> {
    let v = output(Command::new("dpkg-query").args(["-W", "-f=${Status} ${Version}", package]))?;
    let v = v.strip_prefix("install ok installed ")?.trim();
    (!v.is_empty()).then(|| v.to_owned())
}

/// True when `apt-cache` knows `version` of `package` in a configured source.
fn apt_has_version(package: &str, version: &str) -> bool {
    output(Command::new("apt-cache").args(["madison", package])).is_some_and(|s| {
        s.lines()
            .any(|l| l.split('|').nth(1).is_some_and(|v| v.trim() == version))
    })
}

/// Debian's backports suite, added (and announced) only when an installed QEMU package came
/// from it, so that `qemu-system-arm` can be installed at the same version.
const BACKPORTS_SOURCES: &str = "/etc/apt/sources.list.d/stiffwall-backports.sources";

fn add_backports(codename: &str) -> Result<()> {
    let text = format!(
        "Types: deb\nURIs: http://deb.debian.org/debian\nSuites: {codename}-backports\n\
         Components: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n"
    );
    eprintln!("xtask: adding Debian's {codename}-backports suite ({BACKPORTS_SOURCES}) to match the installed QEMU packages");
    std::fs::write(BACKPORTS_SOURCES, text)?;
    let _ = Command::new("apt-get").args(["update", "-q"]).status();
    Ok(())
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

/// Makes sure `qemu-system-arm` is installed, at the version of any QEMU package the machine
/// already has (e.g. a backported `qemu-utils`): installing Debian's default version beside a
/// newer `qemu-utils` would remove it, which a test command must never do.
pub fn ensure_qemu() -> Result<()> {
    if which("qemu-system-arm") {
        return Ok(());
    }
    let pinned = [
        "qemu-system-common",
        "qemu-system-data",
        "qemu-utils",
        "qemu-block-extra",
    ]
    .iter()
    .find_map(|p| installed_version(p));
    match pinned {
        Some(v) => {
            if !apt_has_version("qemu-system-arm", &v) && is_root() && is_debian() {
                if let Some(code) = v.split("~bpo").nth(1).and_then(|s| s.split('+').next()) {
                    let codename = match code {
                        "11" => "bullseye",
                        "12" => "bookworm",
                        "13" => "trixie",
                        _ => "",
                    };
                    if !codename.is_empty() {
                        add_backports(codename)?;
                    }
                }
            }
            let pkgs = [
                format!("qemu-system-arm={v}"),
                format!("qemu-system-common={v}"),
                format!("qemu-system-data={v}"),
            ];
            let pkgs: Vec<&str> = pkgs.iter().map(String::as_str).collect();
            apt_install(
                &pkgs,
                "QEMU (qemu-system-arm, at the installed QEMU version)",
            )?;
        }
        None => apt_install(&["qemu-system-arm"], "QEMU (qemu-system-arm)")?,
    }
    if !which("qemu-system-arm") {
        bail!("qemu-system-arm still not on PATH after installing it");
    }
    Ok(())
}

/// Makes sure Debian's `chromium` and `chromium-driver` are installed (the real-browser test
/// of `hostctl ui` and its screenshots), with [`apt_install`]: nothing is removed.
pub fn ensure_chromium() -> Result<()> {
    if which("chromium") && which("chromedriver") {
        return Ok(());
    }
    apt_install(
        &["chromium", "chromium-driver"],
        "Chromium and ChromeDriver (the browser test of hostctl ui)",
    )?;
    if !(which("chromium") && which("chromedriver")) {
        bail!("chromium or chromedriver still not on PATH after installing them");
    }
    Ok(())
}

/// Makes sure the board emulator's C core (unicorn, built by its `-sys` crate) can build:
/// `cmake` and libclang (for bindgen), with [`apt_install`]: nothing is removed.
pub fn ensure_board_emu_deps() -> Result<()> {
    let libclang = || {
        [
            "/usr/lib/llvm-14/lib",
            "/usr/lib/llvm-15/lib",
            "/usr/lib/llvm-16/lib",
            "/usr/lib/x86_64-linux-gnu",
        ]
        .iter()
        .any(|d| {
            std::fs::read_dir(d).is_ok_and(|rd| {
                rd.flatten()
                    .any(|e| e.file_name().to_string_lossy() == "libclang.so")
            })
        })
    };
    if which("cmake") && libclang() {
        return Ok(());
    }
    apt_install(
        &["cmake", "libclang-dev"],
        "cmake and libclang-dev (the board emulator's unicorn core and its bindings)",
    )?;
    if !which("cmake") {
        bail!("cmake still not on PATH after installing it");
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
