//! Shard merging ([`merge`]): validated shard files of one sweep, in any order, into one
//! complete map.
use std::path::PathBuf;
use stiffwall_sim::map::MapPoint;

use super::error::{ensure, MapFileError, Result};
use super::format::{Cost, MapFile, Panel, Spec};

/// Merges validated shard files of one sweep (any order) into a complete map.
///
/// # Errors
/// Mismatched sweeps or shard counts, a shard given twice, or missing shards.
pub fn merge(files: &[(PathBuf, MapFile)]) -> Result<MapFile> {
    let ordered = shards_in_order(files)?;
    let spec = files[0].1.spec.clone();
    let (panels, ns) = joined_panels(&spec, &ordered);
    let cpu: Option<Vec<f64>> = ordered.iter().map(|f| f.cost.cpu_seconds).collect();
    Ok(MapFile {
        spec_crc64: spec.crc64(),
        spec,
        shard: None,
        cost: Cost::of(&panels, ns)
            .with_cpu_seconds(cpu.map(|c| c.iter().sum()))
            .with_cycle_points(ordered.iter().map(|f| f.cost.cycle_points).sum()),
        panels,
        seconds: ordered.iter().map(|f| f.seconds).sum(),
    })
}

/// The shard files in shard order, once each, all of one sweep and one split.
///
/// # Errors
/// No file, mismatched sweeps or shard counts, a shard given twice, or missing shards.
fn shards_in_order(files: &[(PathBuf, MapFile)]) -> Result<Vec<&MapFile>> {
    let (first_path, first) = files
        .first()
        .ok_or_else(|| MapFileError::Merge("no input files".into()))?;
    let (_, n) = first.shard_or_whole();
    let mut by_k: Vec<Option<usize>> = vec![None; n];
    for (i, (path, f)) in files.iter().enumerate() {
        ensure!(
            Merge,
            f.spec == first.spec,
            "{} and {} belong to different sweeps ({} differs; spec_crc64 {} vs {})",
            first_path.display(),
            path.display(),
            first.spec.first_difference(&f.spec),
            first.spec_crc64,
            f.spec_crc64
        );
        let (k, nf) = f.shard_or_whole();
        ensure!(
            Merge,
            nf == n,
            "{} is shard {k}/{nf} but {} is a shard of {n}: merge shards of one split",
            path.display(),
            first_path.display()
        );
        if let Some(j) = by_k[k] {
            return Err(MapFileError::Merge(format!(
                "shard {k}/{n} given twice: {} and {}",
                files[j].0.display(),
                path.display()
            )));
        }
        by_k[k] = Some(i);
    }
    let missing: Vec<String> = by_k
        .iter()
        .enumerate()
        .filter(|(_, f)| f.is_none())
        .map(|(k, _)| format!("{k}/{n}"))
        .collect();
    ensure!(
        Merge,
        missing.is_empty(),
        "missing shards: {} ({} of {n} given)",
        missing.join(", "),
        n - missing.len()
    );
    Ok(by_k.iter().flatten().map(|&i| &files[i].1).collect())
}

/// Each panel's points from every shard in index order, with their ns per period.
fn joined_panels(spec: &Spec, ordered: &[&MapFile]) -> (Vec<Panel>, Vec<Vec<f64>>) {
    let specs = spec.panels();
    let mut panels = Vec::with_capacity(specs.len());
    let mut ns = Vec::with_capacity(specs.len());
    for (pi, ps) in specs.iter().enumerate() {
        let mut points: Vec<(MapPoint, f64)> = ordered
            .iter()
            .flat_map(|f| {
                let p = &f.panels[pi].points;
                p.iter()
                    .copied()
                    .zip(f.cost.ns_per_period[pi].iter().copied())
            })
            .collect();
        points.sort_by_key(|(p, _)| p.index);
        let (points, c): (Vec<MapPoint>, Vec<f64>) = points.into_iter().unzip();
        panels.push(Panel {
            mu: ps.mu,
            tau_d: ps.tau_d,
            xidot0: ps.xidot0,
            points,
        });
        ns.push(c);
    }
    (panels, ns)
}
