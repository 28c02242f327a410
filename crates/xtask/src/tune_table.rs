//! `cargo xtask tune-table [--quick] [--only NAME]...`: the evidence table of docs/TUNE.md
//! (issue 10, items 5 and 6), generated, never written by hand.
//!
//! Builds `hostctl` (release), then runs `tests/src/bin/tune_table.rs` (release), which for every
//! plant of `sim/plants/` computes the true largest stable stiffness K* with the simulator alone,
//! runs `hostctl tune --plant FILE --fast --dry-run --json`, drives the firmware supervisor at
//! 1.5 K* and writes docs/TUNE.md. `--quick` skips the tune runs (K* and the supervisor only);
//! `--only NAME` restricts to plants by file stem; `--plant FILE` (repeatable) checks your own
//! plant files instead (printed; written only with `--out FILE`); `--no-write` prints without
//! writing.
use anyhow::{bail, Result};

/// Builds hostctl and runs the table program.
pub fn tune_table(args: &[String]) -> Result<()> {
    let mut pass: Vec<String> = Vec::new();
    let mut quick = false;
    let mut i = 0;
    while i < args.len() {
        match args[i].as_str() {
            "--quick" => {
                quick = true;
                pass.push(args[i].clone());
            }
            "--no-write" => pass.push(args[i].clone()),
            "--only" => {
                let Some(v) = args.get(i + 1) else {
                    bail!("--only needs a plant name (a file stem of sim/plants/)");
                };
                pass.push("--only".into());
                pass.push(v.clone());
                i += 1;
            }
            flag @ ("--plant" | "--out") => {
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
                "unknown tune-table option {other:?}; available: --quick, --only NAME, --plant FILE, --out FILE, --no-write"
            ),
        }
        i += 1;
    }
    if !quick {
        let hostctl = crate::build_hostctl()?;
        pass.push("--hostctl".into());
        pass.push(hostctl.to_string_lossy().into_owned());
    }
    crate::run(
        crate::cargo()
            .args([
                "run",
                "--release",
                "-p",
                "stiffwall-tests",
                "--bin",
                "tune_table",
                "--",
            ])
            .args(&pass),
    )
}
