//! `cargo xtask unused-deps` (part of `ci`): every declared dependency of the root workspace is
//! used.
//!
//! Two checks, no tool to install:
//! 1. Every entry of the root `[workspace.dependencies]` is inherited (`workspace = true`) by at
//!    least one member's manifest.
//! 2. Every dependency of every member is used by at least one of the member's compiled units,
//!    by rustc's own `unused_crate_dependencies` lint: one `cargo clippy --workspace
//!    --all-targets` pass with the lint as a warning, read as JSON. Each unit (lib, lib test,
//!    bin, test, bench, example) reports the dependencies *it* does not use, so a report alone
//!    means nothing (an integration test need not use everything the library does); a
//!    dependency is unused when every unit that can see it reports it: all units for a normal
//!    dependency, the test-profile units for a dev-dependency. Build scripts and
//!    platform-specific or disabled optional dependencies are not compiled here and so not
//!    judged.
//!
//! Units: none. Invariants: the pass adds lint flags only for workspace members (clippy's
//! wrapper), so no dependency is rebuilt; the board crates under `firmware/boards/` are their
//! own workspaces and are not covered.

use anyhow::{bail, Context, Result};
use serde_json::Value;
use std::collections::BTreeMap;
use std::io::BufRead as _;
use std::process::Stdio;

/// Runs both checks; fails listing every unused dependency.
pub fn unused_deps() -> Result<()> {
    let mut problems = unused_workspace_entries()?;
    problems.extend(unused_member_deps()?);
    if problems.is_empty() {
        eprintln!("xtask unused-deps: every declared dependency is used");
        Ok(())
    } else {
        bail!(
            "declared but unused dependencies:\n  {}",
            problems.join("\n  ")
        )
    }
}

fn manifest(path: &std::path::Path) -> Result<toml::Table> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    text.parse()
        .with_context(|| format!("parsing {}", path.display()))
}

/// Whether a dependency table (`[dependencies]` etc.) inherits `key` from the workspace.
fn inherits(table: Option<&toml::Value>, key: &str) -> bool {
    table
        .and_then(|t| t.get(key))
        .and_then(|d| d.get("workspace"))
        .and_then(toml::Value::as_bool)
        == Some(true)
}

/// Check 1: `[workspace.dependencies]` entries no member inherits.
fn unused_workspace_entries() -> Result<Vec<String>> {
    let root = crate::firmware::root();
    let top = manifest(&root.join("Cargo.toml"))?;
    let ws = top
        .get("workspace")
        .context("root Cargo.toml has no [workspace]")?;
    let members: Vec<&str> = ws
        .get("members")
        .and_then(toml::Value::as_array)
        .context("[workspace] members")?
        .iter()
        .filter_map(toml::Value::as_str)
        .collect();
    let mut tables = Vec::new();
    for m in &members {
        let t = manifest(&root.join(m).join("Cargo.toml"))?;
        for section in ["dependencies", "dev-dependencies", "build-dependencies"] {
            tables.push(t.get(section).cloned());
        }
        if let Some(targets) = t.get("target").and_then(toml::Value::as_table) {
            for (_, spec) in targets {
                for section in ["dependencies", "dev-dependencies", "build-dependencies"] {
                    tables.push(spec.get(section).cloned());
                }
            }
        }
    }
    let declared = ws
        .get("dependencies")
        .and_then(toml::Value::as_table)
        .context("[workspace.dependencies]")?;
    Ok(declared
        .keys()
        .filter(|k| !tables.iter().any(|t| inherits(t.as_ref(), k)))
        .map(|k| format!("{k}: in [workspace.dependencies] of Cargo.toml, inherited by no member"))
        .collect())
}

/// One dependency of a member, as the lint names it.
#[derive(Debug)]
struct Dep {
    /// Manifest key (`heapless08`).
    key: String,
    /// Crate name in code (`heapless08`, `stiffwall_core`).
    krate: String,
    /// A dev-dependency only.
    dev_only: bool,
}

/// Check 2: member dependencies no compiled unit uses.
/// Member packages by id: (name, dependencies compiled for this platform).
type Members = BTreeMap<String, (String, Vec<Dep>)>;
/// Per package: compiled units (all, test-profile).
type Units = BTreeMap<String, (usize, usize)>;
/// Per (package, crate): how many units report the crate unused.
type Unused = BTreeMap<(String, String), usize>;

fn unused_member_deps() -> Result<Vec<String>> {
    let deps = member_deps()?;
    let (units, unused) = clippy_unused(&deps)?;
    let mut problems = Vec::new();
    for (id, (name, list)) in &deps {
        let (all, test) = units.get(id).copied().unwrap_or_default();
        for d in list {
            let seen_by = if d.dev_only { test } else { all };
            let reported = unused
                .get(&(id.clone(), d.krate.clone()))
                .copied()
                .unwrap_or(0);
            if seen_by > 0 && reported >= seen_by {
                problems.push(format!(
                    "{}: {}dependency of {name}, used by none of its {seen_by} compiled unit(s)",
                    d.key,
                    if d.dev_only { "dev-" } else { "" }
                ));
            }
        }
    }
    Ok(problems)
}

/// The workspace members and their dependencies, from `cargo metadata`.
fn member_deps() -> Result<Members> {
    let out = crate::process::cargo()
        .args(["metadata", "--format-version", "1", "--no-deps"])
        .output()
        .context("running cargo metadata")?;
    if !out.status.success() {
        bail!(
            "cargo metadata failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let meta: Value = serde_json::from_slice(&out.stdout).context("parsing cargo metadata")?;
    let mut deps: Members = BTreeMap::new();
    for p in meta["packages"].as_array().context("metadata packages")? {
        let id = p["id"].as_str().unwrap_or_default().to_string();
        let name = p["name"].as_str().unwrap_or_default().to_string();
        let mut list: Vec<Dep> = Vec::new();
        for d in p["dependencies"].as_array().into_iter().flatten() {
            let kind = d["kind"].as_str();
            if kind == Some("build") || !d["target"].is_null() {
                continue; // build scripts and other platforms are not compiled by this pass
            }
            let key = d["rename"]
                .as_str()
                .or(d["name"].as_str())
                .unwrap_or_default()
                .to_string();
            let dev = kind == Some("dev");
            if let Some(e) = list.iter_mut().find(|e| e.key == key) {
                e.dev_only &= dev;
            } else {
                list.push(Dep {
                    krate: key.replace('-', "_"),
                    key,
                    dev_only: dev,
                });
            }
        }
        deps.insert(id, (name, list));
    }
    Ok(deps)
}

/// One clippy pass with `unused-crate-dependencies`: the units compiled per member and the
/// crates each reports unused.
fn clippy_unused(deps: &Members) -> Result<(Units, Unused)> {
    let mut child = crate::process::cargo()
        .args([
            "clippy",
            "--workspace",
            "--all-targets",
            "--message-format",
            "json",
            "--",
            "-W",
            "unused-crate-dependencies",
        ])
        .stdout(Stdio::piped())
        .spawn()
        .context("running cargo clippy")?;
    // Per package: units (all, test-profile) and, per crate, how many units report it unused.
    let mut units: Units = BTreeMap::new();
    let mut unused: Unused = BTreeMap::new();
    let stdout = child.stdout.take().context("clippy stdout")?;
    for line in std::io::BufReader::new(stdout).lines() {
        let line = line?;
        let Ok(v) = serde_json::from_str::<Value>(&line) else {
            continue;
        };
        let pkg = v["package_id"].as_str().unwrap_or_default().to_string();
        if !deps.contains_key(&pkg) {
            continue;
        }
        let kinds: Vec<&str> = v["target"]["kind"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(Value::as_str)
            .collect();
        if kinds.contains(&"custom-build") {
            continue;
        }
        match v["reason"].as_str() {
            Some("compiler-artifact") => {
                let test = v["profile"]["test"].as_bool() == Some(true)
                    || kinds
                        .iter()
                        .any(|k| ["test", "bench", "example"].contains(k));
                let u = units.entry(pkg).or_default();
                u.0 += 1;
                u.1 += usize::from(test);
            }
            Some("compiler-message")
                if v["message"]["code"]["code"].as_str() == Some("unused_crate_dependencies") =>
            {
                let text = v["message"]["message"].as_str().unwrap_or_default();
                if let Some(krate) = text.split('`').nth(1) {
                    *unused.entry((pkg, krate.to_string())).or_default() += 1;
                }
            }
            _ => {}
        }
    }
    let status = child.wait()?;
    if !status.success() {
        bail!("cargo clippy (unused-crate-dependencies pass) failed with {status}");
    }
    Ok((units, unused))
}
