//! The map JSON file: its computation ([`compute`]), format, full validation, atomic writing
//! and shard merging.
//!
//! Units: dimensionless (Table I), `seconds` of wall time, `ns_per_period` nanoseconds of wall
//! time per simulated period. Panels are ordered slice-major: for each μ (outer), each τ_D,
//! each ξ̇₀ (inner). Invariants: a file is written to a
//! temporary sibling (`<name>.partial-<pid>`) and renamed into place only when complete, so a
//! killed run never leaves a file under the requested name; every file carries
//! `spec_crc64`, the CRC-64/XZ of its spec's compact JSON. A file read from disk is used only
//! after [`validate`]: a valid spec (every field in range, grid size bounded before anything
//! is allocated), the hash, `0 <= k < n`, one panel per (μ, τ_D, ξ̇₀) with those values, and
//! in each panel exactly the points of its shard, in index order, with the β, σ of their index,
//! and one finite, non-negative cost per point. [`merge`] also refuses
//! mismatched sweeps and duplicate or missing shards; its result does not depend on the order
//! of its inputs.

//!
//! Modules: `error` (the error type), `format` (the file's contents and the spec's own
//! checks), `validate` (the full check of a file read from disk) and `merge` (shard merging),
//! re-exported here; reading, writing and computing a file live in this one.

use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};
use stiffwall_sim::map;

mod error;
mod format;
mod merge;
mod validate;

pub use crate::values::Values;
pub use error::{MapFileError, Result};
pub use format::{
    process_cpu_seconds, Cost, MapFile, Panel, Spec, MAX_ALL_PANELS, MAX_ALL_POINTS, MAX_PANELS,
    MAX_SHARDS,
};
pub use merge::merge;
pub use validate::validate;

/// Reads and validates a map file; a truncated file is named as such.
///
/// # Errors
/// An unreadable, truncated, malformed or invalid file.
pub fn read(path: &Path) -> Result<MapFile> {
    let s = std::fs::read_to_string(path).map_err(|source| MapFileError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let f: MapFile = serde_json::from_str(&s).map_err(|error| {
        let path = path.to_path_buf();
        if error.is_eof() {
            MapFileError::Truncated { path, error }
        } else {
            MapFileError::NotAMapFile { path, error }
        }
    })?;
    validate(path, &f)?;
    Ok(f)
}

/// The temporary sibling a file is written to before it is renamed into place.
#[must_use]
pub fn partial_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(format!(".partial-{}", std::process::id()));
    path.with_file_name(name)
}

/// Writes `m` (a [`MapFile`], or any JSON document such as the (K, B) map) atomically: to
/// [`partial_path`], flushed to disk, then renamed onto `path`.
///
/// # Errors
/// A file error, naming the path.
pub fn write<T: Serialize>(path: &Path, m: &T) -> Result<()> {
    let tmp = partial_path(path);
    let result = (|| -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        serde_json::to_writer_pretty(&mut f, m)?;
        f.write_all(b"\n")?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(|source| MapFileError::Write {
        path: path.to_path_buf(),
        source,
    })
}

/// Computes a map (or shard (k, n) of it) with the exact solver, calling `progress` once per
/// point; the cost and CPU time are measured around the computation.
#[must_use]
pub fn compute(
    spec: &Spec,
    shard: Option<(usize, usize)>,
    progress: &(dyn Fn() + Sync),
    opts: map::RunOptions,
) -> MapFile {
    let (k, n) = shard.unwrap_or((0, 1));
    let t0 = std::time::Instant::now();
    let cpu0 = process_cpu_seconds();
    let specs = spec.panels();
    let mut cycle_points = 0;
    let (panels, ns): (Vec<Panel>, Vec<Vec<f64>>) = specs
        .iter()
        .map(|ps| {
            let idx = map::shard(ps, k, n);
            let o = map::run_with(ps, &idx, progress, opts);
            cycle_points += o.cycle_points() as u64;
            let panel = Panel {
                mu: ps.mu,
                tau_d: ps.tau_d,
                xidot0: ps.xidot0,
                points: o.points,
            };
            (panel, o.ns_per_period)
        })
        .unzip();
    MapFile {
        spec: spec.clone(),
        spec_crc64: spec.crc64(),
        shard,
        cost: Cost::of(&panels, ns)
            .with_cpu_seconds(
                cpu0.zip(process_cpu_seconds())
                    .map(|(a, b)| (b - a).max(0.0)),
            )
            .with_cycle_points(cycle_points),
        panels,
        seconds: t0.elapsed().as_secs_f64(),
    }
}
