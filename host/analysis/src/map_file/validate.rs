//! The full check of a map file read from disk ([`validate`]): spec, hash, shard, and every
//! panel's points against the spec.
use std::path::Path;
use stiffwall_sim::map::{self, MapSpec};

use super::error::{ensure, MapFileError, Result};
use super::format::{Cost, MapFile, Panel, MAX_SHARDS};

/// Checks a map file read from `path` completely (see the module header) before any use.
///
/// # Errors
/// The first problem found, naming the file, the field and what was expected.
pub fn validate(path: &Path, f: &MapFile) -> Result<()> {
    let name = path.display();
    f.spec.validate().map_err(|e| MapFileError::InvalidSpec {
        path: path.to_path_buf(),
        source: Box::new(e),
    })?;
    let crc = f.spec.crc64();
    ensure!(
        Content,
        f.spec_crc64 == crc,
        "{name}: spec_crc64 is {:?} but the spec hashes to {crc:?}: the file was edited, is \
         corrupt or was written by an older hostctl; re-run its shard",
        f.spec_crc64
    );
    let (k, n) = f.shard_or_whole();
    ensure!(
        Content,
        (1..=MAX_SHARDS).contains(&n) && k < n,
        "{name}: shard [{k}, {n}]: need 0 <= k < n and 1 <= n <= {MAX_SHARDS}"
    );
    let specs = f.spec.panels();
    ensure!(
        Content,
        f.panels.len() == specs.len(),
        "{name}: {} panels, but the spec has {} ({} mu x {} tau_d x {} xidot0 values)",
        f.panels.len(),
        specs.len(),
        f.spec.mu.len(),
        f.spec.tau_d.len(),
        f.spec.xidot0.len()
    );
    ensure!(
        Content,
        f.seconds.is_finite() && f.seconds >= 0.0,
        "{name}: seconds = {}: need a finite value >= 0",
        f.seconds
    );
    ensure!(
        Content,
        f.cost.ns_per_period.len() == specs.len(),
        "{name}: cost.ns_per_period has {} panels, need {}",
        f.cost.ns_per_period.len(),
        specs.len()
    );
    for (pi, (panel, ps)) in f.panels.iter().zip(&specs).enumerate() {
        validate_panel(&name, f, pi, panel, ps, (k, n))?;
    }
    let recount = Cost::of(&f.panels, f.cost.ns_per_period.clone());
    ensure!(
        Content,
        f.cost.periods_total == recount.periods_total,
        "{name}: cost.periods_total = {}, but the points ran {} periods",
        f.cost.periods_total,
        recount.periods_total
    );
    if let Some(c) = f.cost.cpu_seconds {
        ensure!(
            Content,
            c.is_finite() && c >= 0.0,
            "{name}: cost.cpu_seconds = {c}: need a finite value >= 0"
        );
    }
    Ok(())
}

/// Checks panel `pi` of the map file against its spec `ps`: its (mu, tau_d, xidot0), its
/// points of shard (k, n), their costs, indices, (β, σ) and periods run.
fn validate_panel(
    name: &std::path::Display<'_>,
    f: &MapFile,
    pi: usize,
    panel: &Panel,
    ps: &MapSpec,
    (k, n): (usize, usize),
) -> Result<()> {
    let len = f.spec.len();
    let want = map::shard_len(len, k, n);
    for (field, got, want) in [
        ("mu", panel.mu, ps.mu),
        ("tau_d", panel.tau_d, ps.tau_d),
        ("xidot0", panel.xidot0, ps.xidot0),
    ] {
        ensure!(
            Content,
            got.to_bits() == want.to_bits(),
            "{name}: panel {pi} has {field} = {got}, the spec says {want}"
        );
    }
    ensure!(
        Content,
        panel.points.len() == want,
        "{name}: panel {pi} has {} points; shard {k}/{n} of a {len}-point grid has {want}",
        panel.points.len()
    );
    let ns = &f.cost.ns_per_period[pi];
    ensure!(
        Content,
        ns.len() == panel.points.len() && ns.iter().all(|c| c.is_finite() && *c >= 0.0),
        "{name}: cost.ns_per_period[{pi}]: need one finite value >= 0 per point ({})",
        panel.points.len()
    );
    for (j, pt) in panel.points.iter().enumerate() {
        let index = k + j * n;
        ensure!(
            Content,
            pt.index == index,
            "{name}: panel {pi}, point {j}: index {}, expected {index} (shard {k}/{n})",
            pt.index
        );
        let (beta, sigma) = ps.point(index);
        ensure!(
            Content,
            pt.beta.to_bits() == beta.to_bits() && pt.sigma.to_bits() == sigma.to_bits(),
            "{name}: panel {pi}, point {index}: beta = {}, sigma = {} contradict its index \
             (expected beta = {beta}, sigma = {sigma})",
            pt.beta,
            pt.sigma
        );
        ensure!(
            Content,
            pt.periods_run <= f.spec.periods,
            "{name}: panel {pi}, point {index}: periods_run = {} exceeds the horizon {}",
            pt.periods_run,
            f.spec.periods
        );
    }
    Ok(())
}
