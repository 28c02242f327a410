//! `cargo xtask bench`: what accuracy costs in time (stiffwall-sim).
//!
//! Runs the criterion benches of `sim/benches/solvers.rs` (statistics, reports under
//! `target/criterion/`), then the measurement program `sim/examples/bench_table.rs`, which
//! prints and writes the Markdown table (default `docs/BENCHMARKS-sim.md`) and the Pareto plot
//! `docs/figures/pareto-sim.png`.
//! Its headline times the Fig. 6 set on the paper's grid (β 0–1.2 × 21, σ 0–2 × 34, ξ̇₀ ∈
//! {1, 5, 10, 20}, μ = 100, τ_D = 0, 5·10⁴ periods) through `sim::map::run_with`, the code path of
//! `hostctl map`, with and without cycle detection, and gives ns per period separately for
//! decaying, growing and persistent points. `cargo xtask bench` then copies the tables into
//! `docs/BENCHMARKS.md`.
//!
//! Options: `--quick` (skip criterion, short timing batches), `--no-criterion`,
//! `--out FILE` (Markdown destination), `--figure FILE` (Pareto plot destination).
use anyhow::{bail, Result};

/// Runs the benchmarks and writes the table.
pub fn bench(args: &[String]) -> Result<()> {
    let mut criterion = true;
    let mut pass: Vec<String> = Vec::new();
    let mut i = 0;
    while i < args.len() {
        match args[i].as_str() {
            "--quick" => {
                criterion = false;
                pass.push("--quick".into());
            }
            "--no-criterion" => criterion = false,
            "--out" | "--figure" => {
                let Some(v) = args.get(i + 1) else {
                    bail!("{} needs a file name", args[i]);
                };
                pass.push(args[i].clone());
                pass.push(v.clone());
                i += 1;
            }
            other => bail!(
                "unknown bench option {other:?}; available: --quick, --no-criterion, --out FILE, --figure FILE"
            ),
        }
        i += 1;
    }
    if criterion {
        crate::process::run(crate::process::cargo().args([
            "bench",
            "-p",
            "stiffwall-sim",
            "--bench",
            "solvers",
        ]))?;
    }
    crate::process::run(
        crate::process::cargo()
            .args([
                "run",
                "--release",
                "-p",
                "stiffwall-sim",
                "--example",
                "bench_table",
                "--",
            ])
            .args(&pass),
    )
}
