//! `cargo xtask tune-table [--quick] [--only NAME]...`: the evidence table of docs/TUNE.md
//! (issue 10, items 5 and 6), generated, never written by hand.
//!
//! Runs [`table`] in this process, which for every plant of `sim/plants/` computes the true
//! largest stable stiffness K* with the simulator alone, tunes the fast virtual device running
//! the plant with `stiffwall_tune::tune` (a dry run, as `hostctl tune --plant FILE --fast
//! --dry-run`), drives the firmware supervisor at 1.5 K* and writes docs/TUNE.md. `--quick` skips the tune runs (K* and the supervisor only);
//! `--only NAME` restricts to plants by file stem; `--plant FILE` (repeatable) checks your own
//! plant files instead (printed; written only with `--out FILE`); `--no-write` prints without
//! writing; `--check FILE` compares a fresh run's K* columns with FILE's (stale: an error) and
//! writes nothing. Whatever the options, a row that fails what the docs claim is an error.
use anyhow::{bail, Result};

mod render;
mod row;
mod table;
mod tune_run;
mod verdict;

/// Checks the options and runs the table program.
pub fn tune_table(args: &[String]) -> Result<()> {
    let mut pass: Vec<String> = Vec::new();
    let mut i = 0;
    while i < args.len() {
        match args[i].as_str() {
            "--quick" | "--no-write" => pass.push(args[i].clone()),
            "--only" => {
                let Some(v) = args.get(i + 1) else {
                    bail!("--only needs a plant name (a file stem of sim/plants/)");
                };
                pass.push("--only".into());
                pass.push(v.clone());
                i += 1;
            }
            flag @ ("--plant" | "--out" | "--check") => {
                let Some(v) = args.get(i + 1) else {
                    bail!("{flag} needs a file path");
                };
                // The table program runs from the repository root: make the path absolute.
                let path = std::env::current_dir()
                    .map_or_else(|_| v.into(), |d| d.join(v));
                pass.push(flag.into());
                pass.push(path.to_string_lossy().into_owned());
                i += 1;
            }
            other => bail!(
                "unknown tune-table option {other:?}; available: --quick, --only NAME, --plant FILE, --out FILE, --no-write, --check FILE"
            ),
        }
        i += 1;
    }
    table::generate(&pass)
}

/// The tune tables' check in `cargo xtask ci`: docs/TUNE.md (the plants of `sim/plants/`)
/// and docs/TUNE-holdout.md (`sim/plants-holdout/`) against a fresh run, every tune included:
/// a row that fails what the docs claim (a set wall that does not rest in every run of the
/// criterion, K below 0.7 K*(B), a supervisor that does not stop a run, a median gain below 2
/// over `sim/plants/`) or a stale K* column fails CI.
pub fn ci_checks() -> Result<()> {
    tune_table(&["--check".into(), "docs/TUNE.md".into()])?;
    let dir = crate::firmware::root().join("sim").join("plants-holdout");
    let mut holdout: Vec<std::path::PathBuf> = std::fs::read_dir(&dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    holdout.sort();
    if holdout.is_empty() {
        bail!("no plant files in {}", dir.display());
    }
    let mut args: Vec<String> = vec!["--check".into(), "docs/TUNE-holdout.md".into()];
    for p in &holdout {
        args.push("--plant".into());
        args.push(p.to_string_lossy().into_owned());
    }
    tune_table(&args)
}
