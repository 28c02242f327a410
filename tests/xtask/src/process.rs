//! Running commands for the xtasks: `cargo` in the repository root, a step that fails when its
//! command fails, `cargo test` runs that must run at least N tests, and the Markdown sections
//! the xtasks rewrite. Imports nothing of the crate (every task uses it; it uses none).
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Repository root (the xtask crate lives at tests/xtask).
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .ancestors()
        .nth(2)
        .expect("xtask sits two levels below the root")
        .to_path_buf()
}

/// Runs a command, echoing it, and fails when it fails.
pub fn run(cmd: &mut Command) -> Result<()> {
    eprintln!("xtask: running {cmd:?}");
    let status = cmd.status().with_context(|| format!("starting {cmd:?}"))?;
    if !status.success() {
        bail!("{cmd:?} failed with {status}");
    }
    Ok(())
}

/// Runs the `#[ignore]`d tests of `--test test` in package `pkg` (release build), with
/// `extra` test arguments; fails when they fail, or when fewer than `min` ran (a filter or a
/// rename that leaves nothing to run must not pass in silence).
pub fn run_ignored(pkg: &str, test: &str, extra: &[&str], min: usize) -> Result<()> {
    let mut cmd = cargo();
    cmd.args([
        "test",
        "--release",
        "-p",
        pkg,
        "--test",
        test,
        "--",
        "--ignored",
    ])
    .args(extra);
    run_counting(&mut cmd, min)
}

/// Runs the `cargo test` command `cmd` (its stdout shown), failing when it fails or when fewer
/// than `min` tests passed.
pub fn run_counting(cmd: &mut Command, min: usize) -> Result<()> {
    cmd.stderr(std::process::Stdio::inherit());
    eprintln!("xtask: running {cmd:?}");
    let out = cmd.output().with_context(|| format!("starting {cmd:?}"))?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    print!("{stdout}");
    if !out.status.success() {
        bail!("{cmd:?} failed with {}", out.status);
    }
    let ran = ran_tests(&stdout);
    if ran < min {
        bail!("{cmd:?} ran {ran} test(s), fewer than the {min} it must run");
    }
    Ok(())
}

/// Tests that passed, from libtest's `test result: ok. N passed; …` lines.
fn ran_tests(stdout: &str) -> usize {
    stdout
        .lines()
        .filter_map(|l| l.strip_prefix("test result: ok. "))
        .filter_map(|l| l.split(' ').next()?.parse::<usize>().ok())
        .sum()
}

/// A `cargo` command in the repository root.
pub fn cargo() -> Command {
    let mut c = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    c.current_dir(root());
    c
}

/// Builds the release `hostctl` and returns its path (under `CARGO_TARGET_DIR` when set).
pub fn build_hostctl() -> Result<std::path::PathBuf> {
    run(cargo().args([
        "build",
        "--release",
        "-p",
        "stiffwall-host",
        "--bin",
        "hostctl",
    ]))?;
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map_or_else(|| root().join("target"), std::path::PathBuf::from);
    Ok(target.join("release").join("hostctl"))
}

/// Replaces the text between `<!-- NAME:start -->` and `<!-- NAME:end -->` in a Markdown file
/// (appending the section when absent, creating the file when missing).
pub fn update_section(path: &std::path::Path, name: &str, body: &str) -> Result<()> {
    let start = format!("<!-- {name}:start -->");
    let end = format!("<!-- {name}:end -->");
    let old = std::fs::read_to_string(path).unwrap_or_else(|_| "# Benchmarks\n".into());
    let block = format!("{start}\n{body}\n{end}");
    let new = match (old.find(&start), old.find(&end)) {
        (Some(a), Some(b)) if b > a => format!("{}{block}{}", &old[..a], &old[b + end.len()..]),
        _ => format!("{}\n{block}\n", old.trim_end()),
    };
    std::fs::write(path, new).with_context(|| format!("writing {}", path.display()))
}

#[cfg(test)]
mod tests {
    #[test]
    fn ran_tests_counts_the_passed_tests_of_every_result_line() {
        let out = "running 2 tests\ntest a ... ok\ntest b ... ok\n\ntest result: ok. 2 passed; 0 \
                   failed; 0 ignored\n\ntest result: ok. 1 passed; 0 failed\n";
        assert_eq!(super::ran_tests(out), 3);
        assert_eq!(super::ran_tests("test result: ok. 0 passed; 0 failed"), 0);
        assert_eq!(super::ran_tests(""), 0);
    }
}
