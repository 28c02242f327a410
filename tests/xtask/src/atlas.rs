//! `cargo xtask atlas`: regenerates the stability atlas of the docs — a `hostctl map` sweep over
//! μ ∈ [1, 1000] (log) × τ_D ∈ {0, 0.5, 1, 1.25, 2} at ξ̇₀ = 5, then `hostctl map atlas` into
//! docs/ATLAS.md (agreement fractions and measured cost) and docs/figures/atlas/ (one figure
//! per slice, the summary, the atlas JSON).
//!
//! Units: those of `hostctl map` (dimensionless, Table I). Invariant: every number in
//! docs/ATLAS.md comes from this command; the map JSON itself stays in target/ (large).

use crate::firmware;
use crate::process::run;
use anyhow::{ensure, Result};
use std::process::Command;

/// The sweep's `hostctl map` flags.
pub const MAP_ARGS: &str = "--mu 1:1000:7:log --tau-d 0,0.5,1,1.25,2 --xidot0 5 \
                            --beta 0:3:31 --sigma 0:2:21 --periods 50000";

/// Runs `cargo xtask atlas`.
///
/// # Errors
/// A failed build, sweep or atlas.
pub fn atlas(args: &[String]) -> Result<()> {
    ensure!(args.is_empty(), "atlas takes no arguments (got {args:?})");
    let hostctl = crate::process::build_hostctl()?;
    let root = firmware::root();
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map_or_else(|| root.join("target"), std::path::PathBuf::from);
    let map = target.join("atlas-map.json");
    let figures = root.join("docs/figures/atlas");
    // Old figures of slices no longer in the sweep must not linger.
    let _ = std::fs::remove_dir_all(&figures);
    run(Command::new(&hostctl)
        .arg("map")
        .args(MAP_ARGS.split_whitespace())
        .args(["--quiet", "--force", "--out"])
        .arg(&map))?;
    let generated_by = format!(
        "cargo xtask atlas\n# which runs:\nhostctl map {MAP_ARGS} --out target/atlas-map.json\n\
         hostctl map atlas target/atlas-map.json --out docs/figures/atlas/atlas.json \
         --plots docs/figures/atlas --markdown docs/ATLAS.md"
    );
    run(Command::new(&hostctl)
        .args(["map", "atlas"])
        .arg(&map)
        .arg("--out")
        .arg(figures.join("atlas.json"))
        .arg("--plots")
        .arg(&figures)
        .arg("--markdown")
        .arg(root.join("docs/ATLAS.md"))
        .arg("--generated-by")
        .arg(generated_by)
        .current_dir(&root))
}
